"""Lists the properties Mitsuba 3's plugins read that hppm's plugin table (`hppm plugins`)
does not list, plugin by plugin: what to read next, or to refuse by name.

    git clone --branch v3.9.1 https://github.com/mitsuba-renderer/mitsuba3 /tmp/mitsuba3
    hppm plugins > /tmp/plugins.md
    python3 plugin_properties.py /tmp/mitsuba3 /tmp/plugins.md

A property counts as read when the plugin's source (src/<family>/<kind>.cpp), or its base
class's, asks for it by name (props.get..., has_property, get_texture, ...). The base classes
are over-inclusive: Mesh's and Shape's properties are reported for the analytic shapes,
shapegroups and instances too; `bitmap` and `data` are the Python API's in-memory arguments
and a spectrum's `value` an internal route. As of hppm's sixteenth session the list holds only
those and the area emitter's `to_world` (which Mitsuba refuses too).
"""
import re
import sys
from pathlib import Path

FAMILIES = {"bsdf": "bsdfs", "emitter": "emitters", "shape": "shapes", "texture": "textures",
            "film": "films", "rfilter": "rfilters", "sensor": "sensors",
            "integrator": "integrators", "sampler": "samplers", "spectrum": "spectra"}
BASES = {"shape": ["src/render/shape.cpp", "src/render/mesh.cpp"],
         "emitter": ["src/render/emitter.cpp", "src/render/endpoint.cpp"],
         "sensor": ["src/render/sensor.cpp", "src/render/endpoint.cpp"],
         "film": ["src/render/film.cpp"], "bsdf": ["src/render/bsdf.cpp"],
         "texture": ["src/render/texture.cpp"]}
READ = re.compile(r'props\.(?:get|has_property|get_texture|get_emissive_texture|'
                  r'get_unbounded_texture|get_volume|get_any_texture|try_get|get_spectrum)\w*'
                  r'(?:<[^>]*>)?\(\s*"([A-Za-z_0-9]+)"')


def read_by(path):
    return set(READ.findall(path.read_text())) if path.exists() else None


def main(mitsuba, table):
    mitsuba = Path(mitsuba)
    for line in Path(table).read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) < 3 or cells[0] not in FAMILIES:
            continue
        listed = set(re.findall(r"`([^`]+)`", cells[2]))
        for kind in re.findall(r"`([^`]+)`", cells[1]):
            theirs = read_by(mitsuba / "src" / FAMILIES[cells[0]] / f"{kind}.cpp")
            if theirs is None:
                continue
            for base in BASES.get(cells[0], []):
                theirs |= read_by(mitsuba / base) or set()
            missing = sorted(theirs - listed)
            if missing:
                print(f"{cells[0]} {kind}: {', '.join(missing)}")


if __name__ == "__main__":
    main(*sys.argv[1:3])
