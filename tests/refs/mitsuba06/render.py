#!/usr/bin/env python3
"""Mitsuba 3 references for the public Mitsuba 0.4-0.6 scenes of tests/data/mitsuba06.

Mitsuba 3 reads a file older than 2.0 only after renaming (camelCase to snake_case, <lookAt>);
everything else 0.6 accepted it refuses. So each scene is edited by hand, as a user would, into
a file Mitsuba 3 renders, and the edits are the ones listed here (EDITS), applied by this
script and written to scenes/NAME.xml so that they can be read:

  lookAt       <lookAt> becomes <lookat> (Mitsuba 3.9.1 does not rename it)
  integrator   research or 0.6-only integrators (vrl, sdmm, pmc, photonmap, direct, ...)
               become `path` (`volpath` in a scene with media) with the depth 0.6 used
               (`direct` is depth 2); includes that only choose the integrator are dropped
  properties   properties directly under <scene> are removed (0.6 ignored them)
  sampler      a type Mitsuba 3 lacks (sobol) becomes `independent`
  film         becomes an hdrfilm of the test's reduced size with the original rfilter
               (ldrfilm, gamma, banner, tonemapping only shaped 0.6's output files)
  bitmap       filterType ewa/trilinear removed (Mitsuba 3 filters bilinear, as hppm does)
  spectrum     three plain values become <rgb> (0.6's RGB build read them so)
  media        sigmaA/sigmaS become sigma_t/albedo (Mitsuba 3 reads only those)
  boundary     a shape with a medium and no BSDF gets a null BSDF (0.6's default for a
               medium boundary; Mitsuba 3's is diffuse)
  conductor    no material and no eta/k: material Cu, 0.6's default
  unread       properties Mitsuba 3 then still refuses ("unreferenced property") are removed,
               one at a time, each named in the log

hppm is tested on the files as shipped, with only the film's size changed to the same reduced
size (tests/mitsuba06.rs).

Usage:
  DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so python3 render.py [NAME ...]
      [--passes 16] [--pass-spp 256]
Writes scenes/NAME.xml, images/NAME.exr (the mean of the passes) and prints, per scene, the
figures tests/mitsuba06.rs holds: relMSE of one 256-spp pass against the mean of the others
(pixels and 8x8 blocks: Mitsuba's own error at 256 spp, median over passes) and the
reference's own noise (pixels and blocks). relMSE = mean of (x - ref)^2 / (ref^2 + 0.01).
"""
import argparse, os, re, copy, time, json
import xml.etree.ElementTree as ET
import numpy as np
import mitsuba as mi

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, '..', '..', 'data', 'mitsuba06')

# name: (shipped file under tests/data/mitsuba06, reduced film width, height)
SCENES = {
    'nlvrl_box': ('nlvrl/FBD15ALVRL_box/box.xml', 64, 64),
    'nlvrl_glass': ('nlvrl/FBD15ALVRL_glass/glass/glass.xml', 48, 72),
    'nlvrl_cbox040': ('nlvrl/cbox_v040/cbox.xml', 64, 64),
    'redner_teapot': ('redner/teapot/teapot.xml', 64, 64),
    'redner_teapot_specular': ('redner/teapot_specular/teapot_specular.xml', 64, 64),
    'sdmm_cornell': ('sdmm/cornell-box/cornell-box.xml', 128, 72),
    'sdmm_volumetric_caustic': ('sdmm/volumetric-caustic/volumetric-caustic.xml', 64, 64),
    'optix_sphere': ('optixrenderer/sphere/sphere.xml', 64, 64),
    'lajolla_veach': ('lajolla/veach_mi/mi.xml', 96, 64),
    'lajolla_matpreview': ('lajolla/matpreview/matpreview.xml', 96, 72),
    'lajolla_vol_cbox': ('lajolla/vol_cbox/vol_cbox.xml', 64, 64),
    'gpu_cornell': ('gpu_raytracer/cornellbox/scene.xml', 64, 64),
}

M3_SAMPLERS = {'independent', 'stratified', 'multijitter', 'orthogonal', 'ldsampler'}


def defaults_of(root):
    return {d.get('name'): d.get('value') for d in root.iter('default')}


def substitute(text, values):
    return re.sub(r'\$(\w+)', lambda m: values.get(m.group(1), m.group(0)), text)


def depth_of(integrator, values):
    """The depth 0.6 renders with: maxDepth (substituted), 2 for `direct`, -1 otherwise."""
    if integrator.get('type') == 'direct':
        return 2
    for p in integrator.iter('integer'):
        if p.get('name') in ('maxDepth', 'max_depth'):
            return int(substitute(p.get('value'), values))
    return -1


def edit(name, log):
    path, width, height = SCENES[name]
    shipped = os.path.join(DATA, path)
    root = ET.parse(shipped).getroot()
    values = defaults_of(root)
    # An include that only chooses the integrator: its integrator, substituted.
    integrators = list(root.iter('integrator'))
    for inc in list(root.findall('include')):
        included = ET.parse(os.path.join(os.path.dirname(shipped),
                                         substitute(inc.get('filename'), values))).getroot()
        integrators += list(included.iter('integrator'))
        root.remove(inc)
        log.append(f'include {inc.get("filename")} dropped (it chooses the integrator)')
    depth = depth_of(integrators[0], values) if integrators else -1
    for i in list(root.findall('integrator')):
        root.remove(i)
    media = root.find('.//medium') is not None
    kind = 'volpath' if media else 'path'
    new = ET.Element('integrator', {'type': kind})
    ET.SubElement(new, 'integer', {'name': 'max_depth', 'value': str(depth)})
    root.insert(0, new)
    log.append(f'integrator {integrators[0].get("type") if integrators else "none"} -> '
               f'{kind} max_depth {depth}')
    for child in list(root):
        if child.tag in ('integer', 'float', 'boolean', 'string', 'rgb', 'spectrum'):
            root.remove(child)
            log.append(f'<{child.tag} name="{child.get("name")}"> under <scene> removed')
    for sensor in root.iter('sensor'):
        for sampler in sensor.findall('sampler'):
            if sampler.get('type') not in M3_SAMPLERS:
                log.append(f'sampler {sampler.get("type")} -> independent')
                sampler.set('type', 'independent')
        for film in sensor.findall('film'):
            rfilter = film.find('rfilter')
            sensor.remove(film)
            new = ET.SubElement(sensor, 'film', {'type': 'hdrfilm'})
            ET.SubElement(new, 'integer', {'name': 'width', 'value': str(width)})
            ET.SubElement(new, 'integer', {'name': 'height', 'value': str(height)})
            if rfilter is not None:
                new.append(rfilter)
            log.append(f'film {film.get("type")} -> hdrfilm {width}x{height}')
    for parent in root.iter():
        for s in list(parent.findall('spectrum')):
            v = s.get('value') or ''
            tokens = [t for t in re.split(r'[,\s]+', v) if t]
            if len(tokens) == 3 and ':' not in v:
                s.tag = 'rgb'
                log.append(f'<spectrum name="{s.get("name")}" value="{v}"> -> <rgb>')
    for m in root.iter('medium'):
        if m.get('type') != 'homogeneous':
            continue
        props = {p.get('name'): p for p in m if p.get('name')}
        if 'sigmaA' in props or 'sigmaS' in props:
            val = lambda p: np.array([float(t) for t in re.split(r'[,\s]+', p.get('value').strip())
                                      if t]) * np.ones(3)
            sa = val(props['sigmaA']) if 'sigmaA' in props else np.zeros(3)
            ss = val(props['sigmaS']) if 'sigmaS' in props else np.zeros(3)
            st = sa + ss
            albedo = np.where(st > 0, ss / np.where(st > 0, st, 1), 0)
            for n in ('sigmaA', 'sigmaS'):
                if n in props:
                    m.remove(props[n])
            fmt = lambda a: ', '.join(f'{x:.9g}' for x in a)
            # Mitsuba 3's RGB variants hold an <rgb> to [0, 1]: the largest goes to `scale`.
            peak = float(st.max()) or 1.0
            scale = m.find("float[@name='scale']")
            if scale is None:
                scale = ET.SubElement(m, 'float', {'name': 'scale', 'value': '1'})
            scale.set('value', f'{float(scale.get("value")) * peak:.9g}')
            ET.SubElement(m, 'rgb', {'name': 'sigma_t', 'value': fmt(st / peak)})
            ET.SubElement(m, 'rgb', {'name': 'albedo', 'value': fmt(albedo)})
            log.append(f'medium {m.get("id")}: sigmaA/sigmaS -> sigma_t {fmt(st)} (as '
                       f'{fmt(st / peak)} times scale), albedo {fmt(albedo)}')
        if m.get('name') and m.get('id'):
            del m.attrib['name']
    for t in root.iter('texture'):
        for f in list(t.findall('string')):
            if f.get('name') == 'filterType' and f.get('value') in ('ewa', 'trilinear'):
                t.remove(f)
                log.append(f'bitmap filterType {f.get("value")} removed (bilinear)')
    for t in root.iter('lookAt'):
        t.tag = 'lookat'
        log.append('<lookAt> -> <lookat>')
    for shape in root.iter('shape'):
        medium = any(c.tag in ('ref', 'medium') and c.get('name') in ('interior', 'exterior')
                     for c in shape)
        has_bsdf = any(c.tag == 'bsdf' or (c.tag == 'ref' and not c.get('name')) for c in shape)
        if medium and not has_bsdf and shape.find('emitter') is None:
            ET.SubElement(shape, 'bsdf', {'type': 'null'})
            log.append(f'shape {shape.get("type")} with a medium and no BSDF: null BSDF '
                       f'(0.6\'s default for a medium boundary)')
    for b in root.iter('bsdf'):
        if b.get('type') in ('conductor', 'roughconductor'):
            names = {p.get('name') for p in b}
            if not names & {'material', 'eta', 'k'}:
                ET.SubElement(b, 'string', {'name': 'material', 'value': 'Cu'})
                log.append(f'{b.get("type")}: material Cu (0.6\'s default)')
    return root, os.path.dirname(shipped)


def load_edited(name, log):
    root, folder = edit(name, log)
    out = os.path.join(HERE, 'scenes', f'{name}.xml')
    os.makedirs(os.path.dirname(out), exist_ok=True)
    mi.file_resolver().prepend(folder)
    for _ in range(64):
        ET.ElementTree(root).write(out)
        try:
            return mi.load_file(out, optimize=False), out
        except Exception as e:
            m = re.search(r'unreferenced propert[\s\S]*?- \w+ "(\w+)"', str(e))
            if not m:
                raise
            prop = m.group(1)
            camel = re.sub(r'_(\w)', lambda g: g.group(1).upper(), prop)
            removed = False
            for parent in root.iter():
                for p in list(parent):
                    if p.get('name') in (prop, camel) and p.tag != 'default':
                        parent.remove(p)
                        removed = True
            if not removed:
                raise
            log.append(f'property "{prop}" removed (Mitsuba 3 refuses it)')
    raise RuntimeError('too many edits')


def relmse(x, ref):
    return float(np.mean((x - ref) ** 2 / (ref ** 2 + 0.01)))


def block(a, b=8):
    h, w, c = a.shape
    a = a[: h - h % b, : w - w % b]
    return a.reshape(h // b, b, w // b, b, c).mean(axis=(1, 3))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('names', nargs='*')
    ap.add_argument('--passes', type=int, default=16)
    ap.add_argument('--pass-spp', type=int, default=256)
    args = ap.parse_args()
    mi.set_variant('llvm_ad_rgb')
    figures = {}
    for name in args.names or SCENES:
        log = []
        scene, out = load_edited(name, log)
        print(f'== {name}: {out}')
        for line in log:
            print('   edit:', line)
        passes, times = [], []
        for seed in range(args.passes):
            t = time.time()
            img = np.array(mi.render(scene, spp=args.pass_spp, seed=seed))[:, :, :3]
            times.append(time.time() - t)
            passes.append(img.astype(np.float64))
        passes = np.stack(passes)
        k = len(passes)
        ref = passes.mean(axis=0)
        loo = lambda i: (ref * k - passes[i]) / (k - 1)
        pass_px = float(np.median([relmse(passes[i], loo(i)) for i in range(k)]))
        pass_bl = float(np.median([relmse(block(passes[i]), block(loo(i))) for i in range(k)]))
        noise_px = float(np.mean(passes.var(axis=0, ddof=1) / k / (ref ** 2 + 0.01)))
        bvar = np.stack([block(p) for p in passes]).var(axis=0, ddof=1) / k
        noise_bl = float(np.mean(bvar / (block(ref) ** 2 + 0.01)))
        os.makedirs(os.path.join(HERE, 'images'), exist_ok=True)
        mi.util.write_bitmap(os.path.join(HERE, 'images', f'{name}.exr'),
                             mi.TensorXf(ref.astype(np.float32)))
        figures[name] = dict(pixels_256=pass_px, blocks_256=pass_bl, noise_pixels=noise_px,
                             noise_blocks=noise_bl, spp=k * args.pass_spp,
                             sec_per_pass=float(np.median(times[1:] or times)),
                             mean=[float(x) for x in ref.mean(axis=(0, 1))])
        print(f'   {json.dumps(figures[name])}')
    with open(os.path.join(HERE, 'figures.json'), 'a') as f:
        for name, fig in figures.items():
            f.write(json.dumps({'scene': name, **fig}) + '\n')


if __name__ == '__main__':
    main()
