"""Renders the vertical-step scenes of tests/pixel_filter.rs with Mitsuba 3 and prints each
column's mean (the values in that test's MITSUBA_COLUMNS). Run with Mitsuba 3.9.1 from PyPI:
`python edge_columns.py scalar_rgb` (the llvm variants need a working LLVM). The filters with
negative lobes (MITSUBA_SIGNED_COLUMNS) were rendered with `python edge_columns.py llvm_ad_rgb
signed` (DRJIT_LIBLLVM_PATH set to Debian's libLLVM-19.so), which evaluates the filter exactly
where the scalar variants read a 31-step table."""
import sys, numpy as np
import mitsuba as mi
variant = sys.argv[1]
mi.set_variant(variant)
def scene(width, height, edge_px, rfilter):
    world_x = (2.0 * edge_px / width - 1.0) * 5.0
    return f'''<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="1"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="90"/>
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="4096"/></sampler>
        <film type="hdrfilm">
            <integer name="width" value="{width}"/>
            <integer name="height" value="{height}"/>
            {rfilter}
        </film>
    </sensor>
    <shape type="rectangle">
        <transform name="to_world">
            <scale x="50" y="50"/>
            <translate x="{world_x + 50.0}"/>
        </transform>
        <emitter type="area"><rgb name="radiance" value="1"/></emitter>
    </shape>
</scene>'''
cases = [("", 8.3), ('<rfilter type="gaussian"/>', 1.2), ('<rfilter type="tent"/>', 8.3),
         ('<rfilter type="tent"><float name="radius" value="1.5"/></rfilter>', 0.9),
         ('<rfilter type="tent"><float name="radius" value="1.5"/></rfilter><boolean name="sample_border" value="true"/>', 0.9)]
signed = [('<rfilter type="lanczos"/>', 8.3), ('<rfilter type="lanczos"/>', 0.9),
          ('<rfilter type="lanczos"><integer name="lobes" value="2"/></rfilter>', 1.2),
          ('<rfilter type="lanczos"/><boolean name="sample_border" value="true"/>', 8.3),
          ('<rfilter type="mitchell"/>', 8.3),
          ('<rfilter type="mitchell"><float name="B" value="0.2"/><float name="C" value="0.6"/></rfilter>', 0.9),
          ('<rfilter type="catmullrom"/><boolean name="sample_border" value="true"/>', 0.9)]
if sys.argv[2:] == ["signed"]:
    cases = signed
for rf, edge in cases:
    s = mi.load_string(scene(16, 8, edge, rf))
    img = np.array(mi.render(s, seed=1))
    cols = img[:, :, 0].mean(axis=0)
    print(repr(rf), edge, " ".join(f"{c:.4f}" for c in cols))
