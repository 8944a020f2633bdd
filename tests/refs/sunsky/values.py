#!/usr/bin/env python3
"""Mitsuba 3.9.1's own `sunsky` radiance, for tests/sunsky.rs.

Usage (from anywhere):
  DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so python3 values.py

For each configuration in CONFIGS (the body of an <emitter type="sunsky">, read by Mitsuba from
XML exactly as tests/sunsky.rs gives it to hppm) the `scalar_rgb` variant loads the emitter and
evaluates `emitter.eval(si)` with `si.wi = -d` (Mitsuba's `wi` points away from the emitter:
`BaseSunskyEmitter::eval` looks up `-si.wi`) at 200 world directions d: 100 uniform on the
sphere, 30 in a band about the horizon (local z in [-0.02, 0.05]), 50 within three sun radii
of the sun's centre (half inside its disc) and 20 within 10 degrees of it. Writes values.csv:

  body,config,BODY           the configuration's XML (the rest of the line)
  sun,config,sx,sy,sz        the emitter's world sun direction (its `sun_direction`)
  config,dx,dy,dz,r,g,b      one row per direction

Radiance in Mitsuba's units (RGB variant: W m^-2 sr^-1 per channel as Mitsuba scales them).
"""
import os
import numpy as np
import mitsuba as mi

HERE = os.path.dirname(os.path.abspath(__file__))

# name: body of <emitter type="sunsky">. Each exercises something else: the defaults (Tokyo,
# 2010-07-10 15:00), turbidity and albedo at and between the dataset's levels, low and high
# suns (the elevation interpolation, the sun's disc cut by the horizon), the scales and the
# aperture, a turned frame with the sun given in world space and with the sun from place and
# time, the limb-darkened `complex_sun`.
CONFIGS = {
    'defaults': '',
    'clear_dir': '<vector name="sun_direction" x="0.3" y="-0.5" z="0.7"/>'
                 '<float name="turbidity" value="1.5"/><float name="albedo" value="0"/>',
    'hazy_coloured': '<vector name="sun_direction" x="-0.6" y="0.2" z="0.45"/>'
                     '<float name="turbidity" value="7.3"/><rgb name="albedo" value="0.1, 0.5, 0.9"/>',
    'low_sun': '<vector name="sun_direction" x="0.2" y="0.98" z="0.0175"/>',
    'sun_on_horizon': '<vector name="sun_direction" x="-1" y="0" z="0.0015"/>'
                      '<float name="turbidity" value="2"/>',
    'high_sun': '<vector name="sun_direction" x="0.05" y="0.07" z="0.99"/>'
                '<float name="turbidity" value="5"/><float name="albedo" value="0.6"/>',
    'scaled': '<vector name="sun_direction" x="0.5" y="0.5" z="0.5"/>'
              '<float name="sky_scale" value="0.5"/><float name="sun_scale" value="2.5"/>'
              '<float name="sun_aperture" value="2"/>',
    'turned_dir': '<vector name="sun_direction" x="0.4" y="0.6" z="-0.3"/>'
                  '<transform name="to_world"><rotate x="1" angle="-90"/><rotate y="1" angle="30"/></transform>',
    'paris_time': '<float name="latitude" value="48.85"/><float name="longitude" value="2.35"/>'
                  '<float name="timezone" value="1"/><integer name="year" value="2021"/>'
                  '<integer name="month" value="12"/><integer name="day" value="21"/>'
                  '<float name="hour" value="10"/><float name="minute" value="30"/>'
                  '<float name="second" value="15"/>'
                  '<transform name="to_world"><rotate x="1" angle="-90"/></transform>',
    'complex_sun': '<vector name="sun_direction" x="0.3" y="0.3" z="0.6"/>'
                   '<float name="turbidity" value="4"/><boolean name="complex_sun" value="true"/>',
    'complex_low': '<vector name="sun_direction" x="0" y="-1" z="0.09"/>'
                   '<boolean name="complex_sun" value="true"/><float name="sun_aperture" value="1.5"/>'
                   '<float name="turbidity" value="8"/><rgb name="albedo" value="0.2, 0.3, 0.1"/>',
    'extremes': '<vector name="sun_direction" x="0.7" y="0" z="0.7"/>'
                '<float name="turbidity" value="10"/><float name="albedo" value="1"/>',
}


def unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def around(axis, gamma, phi):
    """Directions at angle gamma from unit `axis`, azimuth phi about it."""
    t = unit(np.cross(axis, [0.0, 0.0, 1.0] if abs(axis[2]) < 0.9 else [1.0, 0.0, 0.0]))
    b = np.cross(axis, t)
    return (np.cos(gamma)[:, None] * axis + np.sin(gamma)[:, None]
            * (np.cos(phi)[:, None] * t + np.sin(phi)[:, None] * b))


def main():
    mi.set_variant('scalar_rgb')
    rng = np.random.default_rng(20250101)
    rows, suns, bodies = [], [], []
    for name, body in CONFIGS.items():
        emitter = mi.load_string(f'<emitter version="3.0.0" type="sunsky">{body}</emitter>')
        params = mi.traverse(emitter)
        sun = np.array(params['sun_direction'], dtype=np.float64)
        to_world = np.array(params['to_world'].matrix, dtype=np.float64)[:3, :3]
        zenith = unit(to_world @ np.array([0.0, 0.0, 1.0]))
        half = np.radians(0.5 * float(dict(
            a.split('"')[1::2][:2] for a in body.split('<float')[1:]).get('sun_aperture', 0.5358)))
        dirs = [unit(rng.normal(size=(100, 3)))]
        # The horizon band: local z in [-0.02, 0.05], any azimuth.
        z = rng.uniform(-0.02, 0.05, 30)
        phi = rng.uniform(0, 2 * np.pi, 30)
        local = np.stack([np.sqrt(1 - z * z) * np.cos(phi), np.sqrt(1 - z * z) * np.sin(phi), z], 1)
        dirs.append(unit(local @ to_world.T))
        # Around the sun: within 3 radii (25 inside the disc, 25 outside), and within 10 degrees.
        dirs.append(around(sun, rng.uniform(0, 0.97, 25) * half, rng.uniform(0, 2 * np.pi, 25)))
        dirs.append(around(sun, rng.uniform(1.03, 3, 25) * half, rng.uniform(0, 2 * np.pi, 25)))
        dirs.append(around(sun, rng.uniform(0, np.radians(10), 20), rng.uniform(0, 2 * np.pi, 20)))
        dirs = np.concatenate(dirs)
        si = mi.SurfaceInteraction3f()
        for d in dirs:
            d32 = mi.ScalarVector3f(*map(float, d))
            si.wi = -d32
            L = emitter.eval(si)
            rows.append(f'{name},{d32[0]:.9g},{d32[1]:.9g},{d32[2]:.9g},'
                        f'{L[0]:.9g},{L[1]:.9g},{L[2]:.9g}')
        suns.append(f'sun,{name},{sun[0]:.9g},{sun[1]:.9g},{sun[2]:.9g}')
        bodies.append(f'body,{name},{body}')
        print(name, 'sun', sun, 'zenith', zenith, 'max', max(float(r.split(",")[4]) for r in rows[-200:]))
    with open(os.path.join(HERE, 'values.csv'), 'w') as f:
        f.write('# Mitsuba 3.9.1 scalar_rgb sunsky radiance, written by values.py\n')
        f.write('\n'.join(bodies + suns + rows) + '\n')


if __name__ == '__main__':
    main()
