"""Writes mitsuba_values.csv: Mitsuba 3's own BSDF values on a table of directions, against
which tests/bsdf.rs checks hppm's CPU reference (each unit's model under src/bsdfs/).

    pip install mitsuba==3.9.1 && python3 mitsuba_table.py

Uses the scalar_rgb variant (no LLVM needed). Each row: material, wi, wo, (u1, u2), then
Mitsuba's eval (f |cos wo|, RGB, radiance mode), pdf, and its sample for (u1, u2): wo, weight
(RGB), pdf, delta (1 when the sampled lobe is a delta lobe).
"""
import math
import random

import mitsuba as mi

mi.set_variant("scalar_rgb")

MATERIALS = {
    "diffuse": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.2, 0.5, 0.8]}},
    "conductor_au": {"type": "conductor", "material": "Au"},
    "conductor_etak": {"type": "conductor", "eta": {"type": "rgb", "value": [0.2, 0.9, 1.1]},
                       "k": {"type": "rgb", "value": [3.9, 2.4, 2.1]},
                       "specular_reflectance": {"type": "rgb", "value": [0.9, 0.8, 0.7]}},
    "roughconductor_au_ggx": {"type": "roughconductor", "material": "Au", "distribution": "ggx", "alpha": 0.18},
    "roughconductor_cu_beckmann_aniso": {"type": "roughconductor", "material": "Cu", "distribution": "beckmann",
                                         "alpha_u": 0.1, "alpha_v": 0.35},
    "roughconductor_ggx_aniso": {"type": "roughconductor", "material": "Ag", "distribution": "ggx",
                                 "alpha_u": 0.4, "alpha_v": 0.08},
    "plastic": {"type": "plastic", "int_ior": 1.5, "ext_ior": 1.0,
                "diffuse_reflectance": {"type": "rgb", "value": [0.1, 0.25, 0.6]}},
    "plastic_nonlinear": {"type": "plastic", "int_ior": 1.7, "nonlinear": True,
                          "diffuse_reflectance": {"type": "rgb", "value": [0.8, 0.5, 0.2]},
                          "specular_reflectance": {"type": "rgb", "value": [0.9, 0.9, 0.6]}},
    "roughplastic_ggx": {"type": "roughplastic", "distribution": "ggx", "alpha": 0.12, "int_ior": 1.5,
                         "ext_ior": 1.0, "diffuse_reflectance": {"type": "rgb", "value": [0.6, 0.12, 0.1]}},
    "roughplastic_beckmann_nonlinear": {"type": "roughplastic", "distribution": "beckmann", "alpha": 0.3,
                                        "nonlinear": True,
                                        "diffuse_reflectance": {"type": "rgb", "value": [0.7, 0.7, 0.3]}},
    "roughdielectric_ggx": {"type": "roughdielectric", "distribution": "ggx", "alpha": 0.1,
                            "int_ior": 1.5, "ext_ior": 1.0},
    "roughdielectric_beckmann_aniso": {"type": "roughdielectric", "distribution": "beckmann",
                                       "alpha_u": 0.3, "alpha_v": 0.1, "int_ior": 1.33, "ext_ior": 1.0},
    "thindielectric": {"type": "thindielectric", "int_ior": 1.5, "ext_ior": 1.0},
    "dielectric": {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0},
    "principled_plain": {"type": "principled", "base_color": {"type": "rgb", "value": [0.8, 0.4, 0.2]},
                         "roughness": 0.4},
    "principled_every_lobe": {"type": "principled", "base_color": {"type": "rgb", "value": [0.9, 0.6, 0.3]},
                              "metallic": 0.3, "roughness": 0.35, "anisotropic": 0.5, "spec_tint": 0.4,
                              "sheen": 0.3, "sheen_tint": 0.5, "clearcoat": 0.6, "clearcoat_gloss": 0.3,
                              "flatness": 0.2, "specular": 0.7},
    "principled_glass": {"type": "principled", "base_color": {"type": "rgb", "value": [0.9, 0.95, 1.0]},
                         "spec_trans": 0.8, "roughness": 0.25, "eta": 1.45},
    "dielectric_tinted": {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0,
                          "specular_reflectance": {"type": "rgb", "value": [0.9, 0.6, 0.3]},
                          "specular_transmittance": {"type": "rgb", "value": [0.2, 0.7, 0.95]}},
    "thindielectric_tinted": {"type": "thindielectric", "int_ior": 1.5, "ext_ior": 1.0,
                              "specular_reflectance": {"type": "rgb", "value": [0.9, 0.6, 0.3]},
                              "specular_transmittance": {"type": "rgb", "value": [0.2, 0.7, 0.95]}},
    "roughdielectric_tinted": {"type": "roughdielectric", "distribution": "ggx", "alpha": 0.2,
                               "int_ior": 1.5, "ext_ior": 1.0,
                               "specular_reflectance": {"type": "rgb", "value": [0.9, 0.6, 0.3]},
                               "specular_transmittance": {"type": "rgb", "value": [0.2, 0.7, 0.95]}},
    "pplastic_ggx": {"type": "pplastic", "distribution": "ggx", "alpha": 0.15, "int_ior": 1.5, "ext_ior": 1.0,
                     "diffuse_reflectance": {"type": "rgb", "value": [0.3, 0.5, 0.7]}},
    "pplastic_beckmann_aniso": {"type": "pplastic", "distribution": "beckmann", "alpha_u": 0.1, "alpha_v": 0.3,
                                "diffuse_reflectance": {"type": "rgb", "value": [0.8, 0.3, 0.1]},
                                "specular_reflectance": {"type": "rgb", "value": [0.9, 0.8, 0.7]}},
    "principledthin_plain": {"type": "principledthin", "base_color": {"type": "rgb", "value": [0.7, 0.3, 0.2]},
                             "roughness": 0.4},
    "principledthin_every_lobe": {"type": "principledthin",
                                  "base_color": {"type": "rgb", "value": [0.8, 0.5, 0.3]},
                                  "roughness": 0.3, "anisotropic": 0.5, "spec_trans": 0.6, "spec_tint": 0.4,
                                  "sheen": 0.5, "sheen_tint": 0.3, "flatness": 0.3, "diff_trans": 0.8,
                                  "eta": 1.33, "specular_reflectance_sampling_rate": 0.7,
                                  "specular_transmittance_sampling_rate": 1.3,
                                  "diffuse_reflectance_sampling_rate": 0.9,
                                  "diffuse_transmittance_sampling_rate": 1.1},
    "principledthin_leaf": {"type": "principledthin", "base_color": {"type": "rgb", "value": [0.2, 0.6, 0.1]},
                            "roughness": 0.5, "spec_trans": 0.2, "diff_trans": 1.2},
}


def direction(rng, lower):
    z = rng.uniform(0.05, 1.0) * (-1 if lower else 1)
    phi = rng.uniform(0, 2 * math.pi)
    r = math.sqrt(1 - z * z)
    return [r * math.cos(phi), r * math.sin(phi), z]


def main():
    rng = random.Random(13)
    rows = []
    for name, desc in MATERIALS.items():
        bsdf = mi.load_dict(desc)
        transmits = "dielectric" in name or "glass" in name or name.startswith("principledthin")
        for i in range(24):
            wi = direction(rng, transmits and i % 3 == 2)
            wo = direction(rng, (transmits and i % 2 == 1) or i == 23)
            u1, u2 = rng.random(), [rng.random(), rng.random()]
            si = mi.SurfaceInteraction3f()
            si.wi = mi.Vector3f(wi)
            si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
            si.wavelengths = []
            ctx = mi.BSDFContext()
            value = bsdf.eval(ctx, si, mi.Vector3f(wo))
            pdf = bsdf.pdf(ctx, si, mi.Vector3f(wo))
            bs, weight = bsdf.sample(ctx, si, u1, mi.Point2f(u2))
            delta = 1 if mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta) else 0
            rows.append([name, *wi, *wo, u1, *u2, *value, pdf, *bs.wo, *weight, bs.pdf, delta])
    with open("mitsuba_values.csv", "w") as f:
        f.write("material,wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,u1,u2_x,u2_y,f_r,f_g,f_b,pdf,"
                "s_wo_x,s_wo_y,s_wo_z,s_r,s_g,s_b,s_pdf,s_delta\n")
        for row in rows:
            f.write(",".join([row[0]] + [repr(float(v)) for v in row[1:]]) + "\n")


main()
