//! The `pppm` estimator node alone on lavapipe with synthetic hit points and deposits, against
//! the same estimate computed on the CPU in f64.

mod common;

use common::pass_harness::{PassHarness, hit_point, hit_point_resource_with};
use common::*;
use glam::Vec3;
use hppm::graph::exec::Wiring;
use hppm::graph::pass::Resource;
use hppm::passes::hit_points::{DEPOSITS, GpuHitPoint, NO_PIXEL, RadiusRule};
use hppm::passes::pppm::{self, Pppm, RadiusSchedule};
use hppm::passes::sppm::MergeParams;

const ALPHA: f64 = 0.7;
/// The global iteration the pass starts at (as a shard or a resumed render would).
const FIRST: u64 = 7;

/// One iteration's hit points and deposits (photon count, flux) per slot.
type Iteration = (Vec<GpuHitPoint>, Vec<(u32, [f32; 3])>);

struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
}

/// Each iteration adds, per pixel, the sum over its slots of flux / (pi r^2) at that
/// iteration's hit points, and 1 to the pixel's count; slots without a hit point, with radius
/// 0 or with no photons add nothing; a NaN deposit drops that pixel's estimate for the
/// iteration (counted in `discarded_samples`, the count not raised). After each iteration the
/// rule it leaves for the camera pass carries the schedule's scale for the next iteration, the
/// first iteration's is set when prepared, and the per-slot radii stay 0 (so the camera takes
/// the rule's radius). Both deposit paths (float atomics and compare-and-swap). Would catch: a
/// wrong normalisation (pi, r^2), estimates that carry state between iterations (the hit points
/// move and their radii change every iteration here), a count that is not one per iteration,
/// a NaN that poisons a pixel, and a radius schedule off by one iteration.
#[test]
fn pppm_adds_each_iterations_density_estimate_to_the_pixel_sums() {
    let gpu = gpu();
    let scene = load_scene("tests/data/scenes/mirror_over_floor.ron");
    let (width, height, slots) = (4u32, 2u32, 2u32);
    let count = (width * height * slots) as usize;
    let pixels = (width * height) as usize;
    let iterations = 4;
    let mut rng = Lcg(5);
    // Per iteration: hit points (fresh positions and radii) and deposits (count, flux).
    let mut plan: Vec<Iteration> = Vec::new();
    for it in 0..iterations {
        let points: Vec<GpuHitPoint> = (0..count)
            .map(|i| {
                let mut hp = hit_point(Vec3::splat(rng.next()), 0.02 + 0.2 * rng.next());
                hp.pixel = i as u32 / slots;
                if i == 5 {
                    hp.pixel = NO_PIXEL;
                }
                if i == 6 {
                    hp.radius = 0.0;
                }
                hp
            })
            .collect();
        let deposits = (0..count)
            .map(|i| {
                let m = if i % 4 == 1 {
                    0
                } else {
                    1 + (rng.next() * 30.0) as u32
                };
                let mut f = [rng.next(), rng.next(), rng.next()].map(|v| v * 0.01 * m as f32);
                if it == 2 && i == 10 {
                    f[1] = f32::NAN;
                }
                (m, f)
            })
            .collect();
        plan.push((points, deposits));
    }
    // The CPU estimate: sums and counts per pixel.
    let mut expected = vec![[0.0f64; 4]; pixels];
    for (points, deposits) in &plan {
        for (pixel, sum) in expected.iter_mut().enumerate() {
            let mut estimate = [0.0f64; 3];
            for slot in 0..slots as usize {
                let i = pixel * slots as usize + slot;
                let (hp, (m, f)) = (&points[i], deposits[i]);
                if hp.pixel == NO_PIXEL || hp.radius <= 0.0 || m == 0 {
                    continue;
                }
                let area = std::f64::consts::PI * (hp.radius as f64).powi(2);
                for c in 0..3 {
                    estimate[c] += f[c] as f64 / area;
                }
            }
            if estimate.iter().all(|v| v.is_finite()) {
                for c in 0..3 {
                    sum[c] += estimate[c];
                }
                sum[3] += 1.0;
            }
        }
    }
    assert_eq!(expected[5][3], iterations as f64 - 1.0, "pixel 5 lost one");

    // The pass holds alpha as the f32 of its params.
    let mut schedule = RadiusSchedule::new(ALPHA as f32 as f64);
    for float_atomics in [gpu.has_float_atomics(), false] {
        let h = PassHarness::new(&gpu, &scene, (width, height), float_atomics);
        let hit_points = hit_point_resource_with(&gpu, slots, &plan[0].0);
        let deposits = Resource::new(
            DEPOSITS,
            gpu.create_buffer(
                "test deposits",
                count as u64 * hppm::passes::hit_points::DEPOSIT_BYTES,
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            )
            .expect("buffer"),
            count as u64,
        );
        let mut pass = Pppm::new(MergeParams {
            alpha: ALPHA as f32,
            ..Default::default()
        });
        let wiring = Wiring {
            consumed: vec!["radiance", "radii"],
            first_iteration: FIRST,
            ..Default::default()
        };
        let out = h.prepare_wired(
            &pppm::KIND,
            &mut pass,
            &[("hit_points", &hit_points), ("deposits", &deposits)],
            &wiring,
        );
        let rule = |gpu: &hppm::gpu::GpuContext| -> RadiusRule {
            out["radii"].read_header(gpu).expect("readback")
        };
        gpu.wait().expect("wait");
        assert_eq!(rule(&gpu).scale, schedule.scale_at(FIRST), "first scale");
        for (it, (points, deposit)) in plan.iter().enumerate() {
            common::pass_harness::write_hit_points(&gpu, &hit_points, points);
            let words: Vec<hppm::passes::hit_points::GpuDepositCell> = deposit
                .iter()
                .map(|(m, f)| hppm::passes::hit_points::GpuDepositCell {
                    count: *m,
                    flux: *f,
                    ..Default::default()
                })
                .collect();
            gpu.queue
                .write_buffer(&deposits.buffer, 0, bytemuck::cast_slice(&words));
            let g = FIRST + it as u64;
            h.run(&mut pass, g, 0);
            let left = rule(&gpu);
            assert_eq!(left.scale, schedule.scale_at(g + 1), "after iteration {g}");
            assert!(left.scale < 1.0 && left.scale > 0.0);
        }
        let radiance: Vec<[f32; 4]> = gpu
            .read_pod(&out["radiance"].buffer, pixels)
            .expect("readback");
        let radii: Vec<f32> = out["radii"].read(&gpu).expect("readback");
        assert!(radii.iter().all(|&r| r == 0.0), "per-slot radii stay 0");
        for (pixel, (gpu_sum, cpu_sum)) in radiance.iter().zip(&expected).enumerate() {
            for c in 0..4 {
                let (a, b) = (gpu_sum[c] as f64, cpu_sum[c]);
                assert!(
                    (a - b).abs() <= 1e-5 * b.abs().max(1e-6),
                    "float atomics {float_atomics}, pixel {pixel}, channel {c}: {a} vs {b}"
                );
            }
        }
        // No photon lies within half a radius here, so each estimate's kernel bias is 4/3 of
        // it, summed and counted like the radiance (a bias left unsummed, or counted once per
        // render, fails).
        let bias: Vec<[f32; 4]> = gpu
            .read_pod(&out["kernel_bias"].buffer, pixels)
            .expect("readback");
        for (pixel, (b, cpu_sum)) in bias.iter().zip(&expected).enumerate() {
            for c in 0..3 {
                let want = 4.0 / 3.0 * cpu_sum[c];
                assert!(
                    (b[c] as f64 - want).abs() <= 1e-5 * want.abs().max(1e-6),
                    "pixel {pixel}, channel {c}: kernel bias {} vs {want}",
                    b[c]
                );
            }
            assert_eq!(b[3] as f64, cpu_sum[3], "pixel {pixel}: estimates counted");
        }
        let counters = hppm::graph::pass::Pass::counters(&pass, &gpu).expect("counters");
        assert_eq!(counters.get("discarded_samples"), 1, "the NaN estimate");
    }
}
