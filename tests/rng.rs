//! The shaders' random streams (shaders/common/rng.wgsl) against their CPU twin
//! (src/passes/rng.rs), draw for draw, on lavapipe. Would catch the two drifting apart, which
//! would void every CPU-side test of the streams (collisions, replayed photon paths).

mod common;

use hppm::gpu::binding::{Access, bind_buffers};
use hppm::gpu::shaders::{ShaderFile, ShaderLibrary};
use hppm::passes::common_modules;
use hppm::passes::rng::Stream;

const DRAWS: u32 = 6;

const PROBE: ShaderFile = ShaderFile {
    path: "tests/rng.rs (probe)",
    source: r#"
#import common::rng::{rng_stream, rng_next_u32, rng_next_f32}

@group(0) @binding(0) var<storage, read> keys: array<vec4<u32>>;
@group(0) @binding(1) var<storage, read_write> words: array<u32>;
@group(0) @binding(2) var<storage, read_write> floats: array<f32>;

@compute @workgroup_size(1, 1, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let key = keys[id.x];
    var rng = rng_stream(key.x, key.y, key.z);
    for (var j = 0u; j < 6u; j++) {
        words[id.x * 6u + j] = rng_next_u32(&rng);
    }
    floats[id.x] = rng_next_f32(&rng);
}
"#,
};

#[test]
fn gpu_streams_equal_the_cpu_mirror() {
    let gpu = common::gpu();
    let keys: Vec<[u32; 4]> = vec![
        [0, 0, 0, 0],
        [1, 0, 0, 0],
        [0, 1, 0, 0],
        [0, 0, 1, 0],
        [(1 << 20) - 1, 99_999, hppm::passes::rng::photon_seed(7), 0],
        [u32::MAX, u32::MAX, u32::MAX, 0],
        [12345, 678, hppm::passes::rng::camera_seed(u64::MAX), 0],
    ];
    let n = keys.len();
    let library = ShaderLibrary::new(
        false,
        Default::default(),
        &common_modules(&hppm::bsdfs::BsdfRegistry::builtin()),
    )
    .expect("library");
    let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
    let key_buffer = gpu
        .create_buffer_init("keys", bytemuck::cast_slice(&keys), storage)
        .expect("keys");
    let words = gpu
        .create_buffer("words", (n as u64) * DRAWS as u64 * 4, storage)
        .expect("words");
    let floats = gpu
        .create_buffer("floats", n as u64 * 4, storage)
        .expect("floats");
    let (layout, group) = bind_buffers(
        &gpu,
        "rng probe",
        &[
            (Access::Read, &key_buffer),
            (Access::ReadWrite, &words),
            (Access::ReadWrite, &floats),
        ],
    );
    let pipeline = library
        .compute_pipeline(&gpu, &PROBE, "main", &[&layout])
        .expect("pipeline");
    let mut recorder = hppm::graph::pass::Recorder::new(&gpu);
    recorder.dispatch("rng probe", &pipeline, &[&group], [n as u32, 1, 1]);
    recorder.flush().expect("run");
    let gpu_words: Vec<u32> = gpu.read_pod(&words, n * DRAWS as usize).expect("read");
    let gpu_floats: Vec<f32> = gpu.read_pod(&floats, n).expect("read");
    for (i, key) in keys.iter().enumerate() {
        let mut stream = Stream::new(key[0], key[1], key[2]);
        let cpu: Vec<u32> = (0..DRAWS).map(|_| stream.next_u32()).collect();
        assert_eq!(
            &gpu_words[i * DRAWS as usize..(i + 1) * DRAWS as usize],
            &cpu[..],
            "key {key:?}"
        );
        assert_eq!(gpu_floats[i], stream.next_f32(), "key {key:?}");
    }
}
