//! Mitsuba's `.vol` grid volumes (src/loaders/vol.rs) and their lookups (src/scene/grid.rs):
//! the reader's round trip and every error it reports, mangled files that must never make it
//! panic, trilinear and nearest lookups against hand-computed values, the cell-centred
//! convention, and the values Mitsuba 3 itself gives for the committed grids
//! (tests/data/volumes/, written by make_smoke.py; Mitsuba's numbers by mitsuba_values.py).

// Mitsuba's values are kept as its script printed them (9 significant digits, which name each
// f32 exactly), not shortened.
#![allow(clippy::excessive_precision)]

use std::path::{Path, PathBuf};

use glam::{Vec3, vec3};
use hppm::loaders::vol::{HEADER_BYTES, MAX_VALUES, encode_vol, parse_vol, read_vol, write_vol};
use hppm::scene::grid::{FilterType, Grid, WrapMode};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/volumes")
        .join(name)
}

/// A fresh directory of this test's own under the system's temporary directory.
fn temp_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hppm_vol_grid_{}_{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A `.vol` header with the given fields (bbox [0, 1]^3).
fn header(version: u8, encoding: i32, res: [i32; 3], channels: i32) -> Vec<u8> {
    let mut out = b"VOL".to_vec();
    out.push(version);
    for v in [encoding, res[0], res[1], res[2], channels] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for v in [0f32, 0.0, 0.0, 1.0, 1.0, 1.0] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    assert_eq!(out.len(), HEADER_BYTES);
    out
}

/// A well-formed file: header then `values`.
fn vol(res: [i32; 3], channels: i32, values: &[f32]) -> Vec<u8> {
    let mut out = header(3, 1, res, channels);
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

/// Reads `bytes` through a file, as the renderer will, and checks that the in-memory parser
/// says the same (its messages lack only the path).
fn read_bytes(dir: &Path, name: &str, bytes: &[u8]) -> Result<Grid, String> {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    let from_file = read_vol(&path);
    let in_memory = parse_vol(bytes);
    match (&from_file, &in_memory) {
        (Ok(a), Ok(b)) => assert_eq!(a, b),
        (Err(a), Err(b)) => {
            assert!(a.starts_with(&path.display().to_string()), "{a}");
            assert!(a.ends_with(b.as_str()), "file: {a}\nmemory: {b}");
        }
        _ => panic!("file and memory disagree: {from_file:?} vs {in_memory:?}"),
    }
    from_file
}

fn expect_error(dir: &Path, name: &str, bytes: &[u8], needles: &[&str]) -> String {
    let message = read_bytes(dir, name, bytes).expect_err(name);
    for needle in needles {
        assert!(
            message.contains(needle),
            "{name}: message {message:?} lacks {needle:?}"
        );
    }
    message
}

fn assert_close(got: Vec3, want: Vec3, tolerance: f32, what: &str) {
    assert!(
        (got - want).abs().max_element() <= tolerance,
        "{what}: got {got}, want {want}"
    );
}

// ----------------------------------------------------------------------------------------------
// Reading and writing

#[test]
fn round_trip_one_and_three_channels() {
    let dir = temp_dir("round_trip");
    for channels in [1u32, 3] {
        let size = [3u32, 2, 4];
        let n = (24 * channels) as usize;
        let values: Vec<f32> = (0..n).map(|i| i as f32 * 0.37 + 0.001).collect();
        let mut grid = Grid::new(size, channels, values);
        grid.bbox_min = vec3(-1.5, 0.25, -3.0);
        grid.bbox_max = vec3(2.0, 0.75, 5.5);
        let path = dir.join(format!("grid{channels}.vol"));
        write_vol(&path, &grid).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(bytes.len(), HEADER_BYTES + 4 * n);
        assert_eq!(read_vol(&path).unwrap(), grid);
        assert_eq!(parse_vol(&bytes).unwrap(), grid);
    }
    // A grid that does not hold together is not written.
    let bad = Grid::new([2, 2, 2], 1, vec![0.0; 7]);
    assert!(write_vol(&dir.join("bad.vol"), &bad).is_err());
    assert!(!dir.join("bad.vol").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_writer_lays_out_bytes_as_the_python_script_does() {
    // ramp.vol was written by make_smoke.py with numpy: the same grid encodes to the same bytes,
    // so the header's field order and the x-fastest value order agree with the format's
    // documentation (src/volumes/grid.cpp), not only with this crate's own reader.
    let mut values = Vec::new();
    for _z in 0..2 {
        for _y in 0..2 {
            values.extend([0.5f32, 1.5]);
        }
    }
    let ramp = Grid::new([2, 2, 2], 1, values);
    assert_eq!(
        encode_vol(&ramp).unwrap(),
        std::fs::read(data("ramp.vol")).unwrap()
    );
    assert_eq!(read_vol(&data("ramp.vol")).unwrap(), ramp);

    // rgb.vol: channel c of cell (x, y, z) is 0.25 (x + 1) + 0.5 y + 0.125 z + 0.1 c.
    let rgb = read_vol(&data("rgb.vol")).unwrap();
    assert_eq!((rgb.size, rgb.channels), ([3, 2, 2], 3));
    for z in 0..2 {
        for y in 0..2 {
            for x in 0..3 {
                let base = 0.25 * (x + 1) as f32 + 0.5 * y as f32 + 0.125 * z as f32;
                let want = vec3(base, base + 0.1, base + 0.2);
                assert_close(rgb.cell(x, y, z), want, 1e-6, "rgb.vol cell");
                let i = rgb.index(x, y, z);
                assert_eq!(i, (((z * 2 + y) * 3 + x) * 3) as usize);
            }
        }
    }
    assert_eq!(rgb.max(), 1.575);
    assert_eq!(rgb.max_per_channel(), vec![1.375, 1.475, 1.575]);
}

#[test]
fn the_committed_smoke_grid() {
    let smoke = read_vol(&data("smoke.vol")).unwrap();
    assert_eq!((smoke.size, smoke.channels), ([24, 24, 24], 1));
    assert_eq!(smoke.data.len(), 24 * 24 * 24);
    assert_eq!(
        (smoke.bbox_min, smoke.bbox_max),
        (Vec3::splat(-1.0), Vec3::ONE)
    );
    // make_smoke.py divides by the maximum: Mitsuba 3.9.1's `max()` is 1 too.
    assert_eq!(smoke.max(), 1.0);
    assert_eq!(smoke.max_per_channel(), vec![1.0]);
    assert!(smoke.data.iter().all(|&v| (0.0..=1.0).contains(&v)));
    let mean = smoke.data.iter().sum::<f32>() / smoke.data.len() as f32;
    assert!((0.05..0.3).contains(&mean), "mean density {mean}");
    assert_eq!(read_vol(&data("ramp.vol")).unwrap().max(), 1.5);
}

// ----------------------------------------------------------------------------------------------
// Errors

#[test]
fn missing_file() {
    let dir = temp_dir("missing");
    let message = read_vol(&dir.join("no_such.vol")).unwrap_err();
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        message.contains("cannot open grid volume file"),
        "{message}"
    );
    assert!(message.contains("no_such.vol"), "{message}");
}

#[test]
fn short_files_and_wrong_headers() {
    let dir = temp_dir("headers");
    let good = vol([2, 1, 1], 1, &[0.25, 0.5]);
    expect_error(&dir, "empty.vol", &[], &["0 bytes", "48-byte header"]);
    expect_error(&dir, "vo.vol", b"VO", &["2 bytes", "48-byte header"]);
    expect_error(
        &dir,
        "half.vol",
        &good[..30],
        &["30 bytes", "48-byte header"],
    );
    expect_error(&dir, "47.vol", &good[..47], &["47 bytes", "48-byte header"]);

    let mut magic = good.clone();
    magic[..3].copy_from_slice(b"PLY");
    expect_error(
        &dir,
        "magic.vol",
        &magic,
        &["not a Mitsuba grid volume", "'P' 'L' 'Y'"],
    );
    expect_error(
        &dir,
        "short_magic.vol",
        b"X",
        &["not a Mitsuba grid volume", "'X'"],
    );
    let mut binary = good.clone();
    binary[..3].copy_from_slice(&[0x00, 0xff, b'L']);
    expect_error(&dir, "binary.vol", &binary, &["0x00 0xff 'L'"]);

    for version in [0u8, 2, 4, 255] {
        let mut bytes = good.clone();
        bytes[3] = version;
        expect_error(
            &dir,
            "version.vol",
            &bytes,
            &[&format!("version {version}")],
        );
    }
    for encoding in [0, 2, 3, -1] {
        let mut bytes = header(3, encoding, [2, 1, 1], 1);
        bytes.extend_from_slice(&good[HEADER_BYTES..]);
        expect_error(
            &dir,
            "encoding.vol",
            &bytes,
            &[&format!("encoding {encoding}")],
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_resolutions_and_channel_counts() {
    let dir = temp_dir("resolution");
    for res in [
        [0, 1, 1],
        [4, 0, 4],
        [1, 1, 0],
        [-1, 2, 2],
        [2, i32::MIN, 2],
    ] {
        let bytes = vol(res, 1, &[0.5; 4]);
        expect_error(&dir, "res.vol", &bytes, &["at least one cell"]);
    }
    // Absurd sizes are refused from the header alone: nothing near their size is allocated.
    let absurd = [
        ([1 << 11, 1 << 10, 1 << 10], 1), // 2^31 cells
        ([2048, 2048, 2048], 3),
        ([i32::MAX, i32::MAX, i32::MAX], 3), // would overflow u64
        ([1 << 10, 1 << 10, 1 << 10], 3),
    ];
    for (res, channels) in absurd {
        let bytes = vol(res, channels, &[1.0; 8]);
        expect_error(
            &dir,
            "absurd.vol",
            &bytes,
            &["more than the", &MAX_VALUES.to_string()],
        );
    }
    // The largest grid accepted, 2^30 values, claimed by an 80-byte file: refused as truncated
    // by the lengths alone, before its 4 GiB are allocated.
    let bytes = vol([1 << 10, 1 << 10, 1 << 10], 1, &[1.0; 8]);
    let expected = (HEADER_BYTES as u64 + 4 * MAX_VALUES).to_string();
    expect_error(
        &dir,
        "huge.vol",
        &bytes,
        &["truncated", &expected, "the file has 80"],
    );

    for channels in [0, 2, 4, 6, -3, i32::MAX] {
        let bytes = vol([1, 1, 1], channels, &[0.5; 6]);
        let m = expect_error(
            &dir,
            "channels.vol",
            &bytes,
            &[&format!("{channels} channels")],
        );
        assert!(m.contains("1 (a scalar such as density) or 3 (RGB)"), "{m}");
        assert_eq!(m.contains("SGGX"), channels == 6, "{m}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn truncated_and_trailing_data() {
    let dir = temp_dir("lengths");
    let values: Vec<f32> = (0..24).map(|i| i as f32).collect();
    let good = vol([2, 3, 4], 1, &values);
    assert_eq!(good.len(), 48 + 96);
    expect_error(
        &dir,
        "cut.vol",
        &good[..good.len() - 6],
        &[
            "truncated",
            "need 144 bytes",
            "24 values",
            "the file has 138",
            "6 missing",
        ],
    );
    expect_error(
        &dir,
        "header_only.vol",
        &good[..48],
        &["truncated", "need 144 bytes", "the file has 48"],
    );
    let mut long = good.clone();
    long.extend_from_slice(&[0, 0, 0]);
    expect_error(
        &dir,
        "long.vol",
        &long,
        &["3 trailing bytes", "need 144 bytes", "the file has 147"],
    );
    let mut rgb = vol([2, 1, 1], 3, &[0.0; 6]);
    rgb.extend_from_slice(&7f32.to_le_bytes());
    expect_error(
        &dir,
        "rgb_long.vol",
        &rgb,
        &["4 trailing bytes", "3 channel(s)", "need 72 bytes"],
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_values_are_named_by_index_and_cell() {
    let dir = temp_dir("values");
    let cases: [(f32, &str); 4] = [
        (-0.5, "is -0.5"),
        (f32::NAN, "is NaN"),
        (f32::INFINITY, "is inf"),
        (f32::NEG_INFINITY, "is -inf"),
    ];
    for (bad, shown) in cases {
        // 3 x 2 x 2, one channel: value 7 is cell x=1 y=0 z=1.
        let mut values = vec![0.25f32; 12];
        values[7] = bad;
        values[9] = -1.0; // a later bad value is not the one named
        let bytes = vol([3, 2, 2], 1, &values);
        let m = expect_error(
            &dir,
            "bad.vol",
            &bytes,
            &["value 7 ", "cell x=1 y=0 z=1)", shown],
        );
        assert!(m.contains("finite and non-negative"), "{m}");
        // Three channels: value 16 is cell 5 (x=2 y=1 z=0), channel 1.
        let mut values = vec![0.25f32; 36];
        values[16] = bad;
        let bytes = vol([3, 2, 2], 3, &values);
        expect_error(
            &dir,
            "bad3.vol",
            &bytes,
            &["value 16 ", "cell x=2 y=1 z=0 channel 1)", shown],
        );
    }
    // Negative zero and zero are fine.
    let grid = read_bytes(&dir, "zeros.vol", &vol([2, 1, 1], 1, &[-0.0, 0.0])).unwrap();
    assert_eq!(grid.max(), 0.0);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A small deterministic generator (SplitMix64) for the mangling loop.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Whatever `bytes` hold, the reader answers without panicking, and a grid it accepts holds
/// together and can be looked up anywhere.
fn survives(bytes: &[u8], rng: &mut SplitMix) {
    if let Ok(grid) = parse_vol(bytes) {
        grid.check().unwrap();
        assert!(grid.data.iter().all(|v| v.is_finite() && *v >= 0.0));
        for _ in 0..4 {
            let p = vec3(rng.unit(), rng.unit(), rng.unit()) * 3.0 - 1.0;
            for filter in [FilterType::Trilinear, FilterType::Nearest] {
                for wrap in [WrapMode::Clamp, WrapMode::Repeat, WrapMode::Mirror] {
                    let v = grid.eval_with(p, filter, wrap);
                    assert!(v.is_finite() && v.min_element() >= 0.0, "{v}");
                }
            }
        }
        for p in [
            Vec3::splat(f32::NAN),
            Vec3::splat(1e30),
            Vec3::splat(-f32::MAX),
        ] {
            let _ = grid.eval_with(p, FilterType::Trilinear, WrapMode::Mirror);
            let _ = grid.eval_with(p, FilterType::Nearest, WrapMode::Repeat);
            let _ = grid.eval(p);
        }
    }
}

#[test]
fn mangled_files_never_panic() {
    let mut rng = SplitMix(0x5eed_0001);
    let files: Vec<Vec<u8>> = ["ramp.vol", "rgb.vol", "smoke.vol"]
        .iter()
        .map(|f| std::fs::read(data(f)).unwrap())
        .collect();
    for file in &files {
        assert!(parse_vol(file).is_ok());
        // Every truncation (of the small files; of smoke.vol's header and a sample beyond).
        for len in 0..file.len().min(400) {
            assert!(parse_vol(&file[..len]).is_err(), "truncated to {len}");
        }
        for _ in 0..200 {
            let len = rng.below(file.len());
            assert!(parse_vol(&file[..len]).is_err());
        }
        // Random byte flips, half of them in the header.
        for round in 0..3000 {
            let mut bytes = file.clone();
            for _ in 0..1 + rng.below(4) {
                let at = if round % 2 == 0 {
                    rng.below(HEADER_BYTES)
                } else {
                    rng.below(bytes.len())
                };
                bytes[at] = rng.next() as u8;
            }
            survives(&bytes, &mut rng);
        }
        // Whole header fields replaced by extreme or random integers.
        for _ in 0..2000 {
            let mut bytes = file.clone();
            let field = 4 + 4 * rng.below(11);
            let value: i32 = match rng.below(6) {
                0 => i32::MAX,
                1 => i32::MIN,
                2 => -1,
                3 => 0,
                4 => rng.below(8) as i32,
                _ => rng.next() as i32,
            };
            bytes[field..field + 4].copy_from_slice(&value.to_le_bytes());
            survives(&bytes, &mut rng);
            // ... and the file cut or padded as well.
            let len = rng.below(bytes.len() + 64);
            bytes.resize(len, rng.next() as u8);
            survives(&bytes, &mut rng);
        }
    }
    // Random garbage, with and without a valid magic and version.
    for _ in 0..2000 {
        let len = rng.below(200);
        let mut bytes: Vec<u8> = (0..len).map(|_| rng.next() as u8).collect();
        if len >= 4 && rng.below(2) == 0 {
            bytes[..4].copy_from_slice(b"VOL\x03");
            if len >= 8 {
                bytes[4..8].copy_from_slice(&1i32.to_le_bytes());
            }
        }
        survives(&bytes, &mut rng);
    }
    // A few of the mangled files through read_vol too (its length checks before reading).
    let dir = temp_dir("mangled");
    for i in 0..50 {
        let mut bytes = files[i % 3].clone();
        let at = rng.below(HEADER_BYTES);
        bytes[at] = rng.next() as u8;
        let len = rng.below(bytes.len() + 8);
        bytes.resize(len, 0x7f);
        let path = dir.join("m.vol");
        std::fs::write(&path, &bytes).unwrap();
        assert_eq!(read_vol(&path).is_ok(), parse_vol(&bytes).is_ok());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

// ----------------------------------------------------------------------------------------------
// Lookups

/// 2 x 1 x 1 cells holding 0 and 1.
fn two_cells() -> Grid {
    Grid::new([2, 1, 1], 1, vec![0.0, 1.0])
}

#[test]
fn values_sit_at_cell_centres() {
    // Mitsuba 3 (Dr.Jit's tex_eval) puts cell i's value at (i + 0.5) / res: with two cells along
    // x, at 1/4 and 3/4. Node-centred samples (value i at i / (res - 1), at 0 and 1) would give
    // the identity x here instead, and fail every assertion but the middle one.
    let g = two_cells();
    let at = |x: f32| g.eval(vec3(x, 0.5, 0.5)).x;
    assert_eq!(at(0.25), 0.0);
    assert_eq!(at(0.75), 1.0);
    assert_eq!(at(0.5), 0.5);
    assert_eq!(at(0.375), 0.25);
    assert_eq!(at(0.625), 0.75);
    // Between a face and the outermost centre the value is the outer cell's (clamp).
    assert_eq!(at(0.0), 0.0);
    assert_eq!(at(0.1), 0.0);
    assert_eq!(at(0.9), 1.0);
    assert_eq!(at(1.0), 1.0);
    // A node-centred lookup would have given these:
    for (x, node_centred) in [(0.1f32, 0.1f32), (0.25, 0.25), (0.9, 0.9)] {
        assert!((at(x) - node_centred).abs() > 0.09, "x = {x}");
    }
    // Nearest: the cell the point lies in, switching at the cells' shared face x = 1/2.
    let near = |x: f32| g.eval_nearest(vec3(x, 0.5, 0.5)).x;
    assert_eq!(
        (near(0.0), near(0.49), near(0.5), near(0.99), near(1.0)),
        (0.0, 0.0, 1.0, 1.0, 1.0)
    );
    // The same along y and z (each axis by its own resolution).
    let gy = Grid::new([1, 4, 1], 1, vec![0.0, 1.0, 2.0, 3.0]);
    for (y, want) in [
        (0.125f32, 0.0f32),
        (0.375, 1.0),
        (0.5, 1.5),
        (0.8125, 2.75),
        (1.0, 3.0),
    ] {
        let got = gy.eval(vec3(0.3, y, 0.9)).y;
        assert!((got - want).abs() < 1e-6, "y = {y}: {got}");
    }
    let gz = Grid::new([1, 1, 3], 1, vec![3.0, 6.0, 0.0]);
    for (z, want) in [
        (0.0f32, 3.0f32),
        (1.0 / 6.0, 3.0),
        (0.5, 6.0),
        (2.0 / 3.0, 3.0),
        (1.0, 0.0),
    ] {
        let got = gz.eval(vec3(0.2, 0.7, z)).z;
        assert!((got - want).abs() < 1e-5, "z = {z}: {got}");
    }
}

#[test]
fn trilinear_against_hand_computed_values() {
    // 2 x 2 x 2 cells with value 1 + x + 2y + 4z at cell (x, y, z), i.e. data 1..=8 in order.
    // Trilinear interpolation reproduces the linear function: with t = clamp(2p - 1/2, 0, 1)
    // per axis, the value at p is 1 + tx + 2 ty + 4 tz.
    let g = Grid::new([2, 2, 2], 1, (1..=8).map(|v| v as f32).collect());
    let t = |p: f32| (2.0 * p - 0.5).clamp(0.0, 1.0);
    let linear = |p: Vec3| 1.0 + t(p.x) + 2.0 * t(p.y) + 4.0 * t(p.z);
    let points = [
        (Vec3::ZERO, 1.0),          // a corner of the cube: cell (0, 0, 0)
        (Vec3::ONE, 8.0),           // the opposite corner
        (vec3(1.0, 0.0, 0.0), 2.0), // other corners
        (vec3(0.0, 1.0, 1.0), 7.0),
        (Vec3::splat(0.5), 4.5),  // the centre: the mean of all eight
        (Vec3::splat(0.25), 1.0), // cell centres
        (vec3(0.75, 0.25, 0.75), 6.0),
        (vec3(0.5, 0.25, 0.25), 1.5), // between two centres
        (vec3(0.6, 0.7, 0.4), 1.0 + 0.7 + 1.8 + 1.2),
        (vec3(0.3, 0.95, 0.55), 1.0 + 0.1 + 2.0 + 2.4),
    ];
    for (p, want) in points {
        assert!((linear(p) - want).abs() < 1e-5, "hand value at {p}");
        assert_close(g.eval(p), Vec3::splat(want), 2e-6, &format!("eval at {p}"));
    }
    // A product term (trilinear interpolation is exact for it too): only cell (1, 1, 1) is 1,
    // so the value is tx * ty * tz.
    let mut corner = vec![0.0f32; 8];
    corner[7] = 1.0;
    let g = Grid::new([2, 2, 2], 1, corner);
    for p in [
        vec3(0.6, 0.7, 0.4),
        vec3(0.3, 0.45, 0.7),
        vec3(0.9, 0.1, 0.55),
        Vec3::splat(0.5),
    ] {
        let want = t(p.x) * t(p.y) * t(p.z);
        assert_close(
            g.eval(p),
            Vec3::splat(want),
            1e-6,
            &format!("product at {p}"),
        );
    }
    // Three channels are interpolated each on its own.
    let rgb = Grid::new([2, 1, 1], 3, vec![0.0, 1.0, 2.0, 4.0, 3.0, 2.0]);
    assert_close(
        rgb.eval(vec3(0.5, 0.1, 0.9)),
        vec3(2.0, 2.0, 2.0),
        1e-6,
        "rgb middle",
    );
    assert_close(
        rgb.eval(vec3(0.375, 0.1, 0.9)),
        vec3(1.0, 1.5, 2.0),
        1e-6,
        "rgb quarter",
    );
    assert_close(
        rgb.eval_nearest(vec3(0.7, 0.1, 0.9)),
        vec3(4.0, 3.0, 2.0),
        0.0,
        "rgb nearest",
    );
}

#[test]
fn wrap_modes_by_hand() {
    // Two cells (0 and 1) along x; Dr.Jit wraps each integer index a lookup touches.
    let g = two_cells();
    let at = |x: f32, wrap| {
        g.eval_with(vec3(x, 0.5, 0.5), FilterType::Trilinear, wrap)
            .x
    };
    // x = 1: halfway between cell 1 (index 1) and index 2, which repeat reads as cell 0, mirror
    // and clamp as cell 1.
    assert_eq!(at(1.0, WrapMode::Repeat), 0.5);
    assert_eq!(at(1.0, WrapMode::Mirror), 1.0);
    assert_eq!(at(1.0, WrapMode::Clamp), 1.0);
    // x = 1.25: the centre of index 2.
    assert_eq!(at(1.25, WrapMode::Repeat), 0.0);
    assert_eq!(at(1.25, WrapMode::Mirror), 1.0);
    // x = 1.75: the centre of index 3, which repeat reads as cell 1 and mirror as cell 0 (the
    // reflection of the reflected grid).
    assert_eq!(at(1.75, WrapMode::Repeat), 1.0);
    assert_eq!(at(1.75, WrapMode::Mirror), 0.0);
    // x = -0.25: index -1, repeat: cell 1; mirror: cell 0.
    assert_eq!(at(-0.25, WrapMode::Repeat), 1.0);
    assert_eq!(at(-0.25, WrapMode::Mirror), 0.0);
    assert_eq!(at(-0.25, WrapMode::Clamp), 0.0);
    // x = 0: halfway between index -1 and 0.
    assert_eq!(at(0.0, WrapMode::Repeat), 0.5);
    assert_eq!(at(0.0, WrapMode::Mirror), 0.0);
    // Repeat is periodic over the unit cube.
    let smoke = read_vol(&data("smoke.vol")).unwrap();
    for p in [vec3(0.3, 0.6, 0.1), vec3(0.97, 0.02, 0.5)] {
        let a = smoke.eval_with(p, FilterType::Trilinear, WrapMode::Repeat);
        let b = smoke.eval_with(
            p + vec3(2.0, -1.0, 3.0),
            FilterType::Trilinear,
            WrapMode::Repeat,
        );
        assert_close(a, b, 1e-5, "repeat period");
    }
}

#[test]
fn ramp_density_and_its_optical_depth() {
    // ramp.vol (make_smoke.py): 0.5 at x = 0, 1.5 at x = 1, so the density is 0.5 up to
    // x = 1/4, exactly 2x to x = 3/4 and 1.5 beyond, whatever y and z.
    let ramp = read_vol(&data("ramp.vol")).unwrap();
    let density = |x: f32, y: f32, z: f32| ramp.eval(vec3(x, y, z)).x;
    let exact = |x: f32| (2.0 * x).clamp(0.5, 1.5);
    for x in [0.0f32, 0.1, 0.25, 0.3, 0.5, 0.6, 0.75, 0.8, 1.0] {
        for (y, z) in [(0.5f32, 0.5f32), (0.0, 1.0), (0.3, 0.8)] {
            let got = density(x, y, z);
            assert!((got - exact(x)).abs() < 1e-6, "x = {x}: {got}");
        }
    }
    // The optical depth across the cube along x is 1, and t^2 + 1/16 up to t in [1/4, 3/4].
    let steps = 4000;
    let depth = |t: f32| -> f64 {
        let h = t as f64 / steps as f64;
        (0..steps)
            .map(|i| density(((i as f64 + 0.5) * h) as f32, 0.3, 0.7) as f64 * h)
            .sum()
    };
    assert!((depth(1.0) - 1.0).abs() < 1e-5, "{}", depth(1.0));
    assert!(
        (depth(0.6) - (0.36 + 0.0625)).abs() < 1e-5,
        "{}",
        depth(0.6)
    );
    assert!((depth(0.2) - 0.1).abs() < 1e-5, "{}", depth(0.2));
}

#[test]
fn grid_bbox_maps_onto_the_unit_cube() {
    let smoke = read_vol(&data("smoke.vol")).unwrap();
    let m = smoke.bbox_transform().unwrap();
    assert_close(
        m.transform_point3(Vec3::splat(-1.0)),
        Vec3::ZERO,
        0.0,
        "min corner",
    );
    assert_close(m.transform_point3(Vec3::ONE), Vec3::ONE, 0.0, "max corner");
    assert_close(
        m.transform_point3(vec3(0.0, 0.5, -0.5)),
        vec3(0.5, 0.75, 0.25),
        0.0,
        "inside",
    );
    let mut flat = smoke.clone();
    flat.bbox_max.y = flat.bbox_min.y;
    assert!(flat.bbox_transform().is_none());
    flat.bbox_max = Vec3::splat(f32::NAN);
    assert!(flat.bbox_transform().is_none());
    let mut inverted = smoke.clone();
    inverted.bbox_min = Vec3::splat(2.0);
    assert!(inverted.bbox_transform().is_none());
}

// ----------------------------------------------------------------------------------------------
// Against Mitsuba 3 itself

/// Compares `grid`'s lookups with Mitsuba's at world points of a `gridvolume` with an identity
/// `to_world` (so the world point is the lookup's point of the unit cube).
fn check_mitsuba(grid: &Grid, filter: FilterType, wrap: WrapMode, rows: &[([f32; 3], [f32; 3])]) {
    for &(p, want) in rows {
        let got = grid.eval_with(Vec3::from(p), filter, wrap);
        // Bit for bit: the lookup does Dr.Jit's f32 operations in Dr.Jit's order (fused
        // multiply-adds where it has them), and the values printed with 9 digits are exact.
        assert_eq!(
            got,
            Vec3::from(want),
            "{filter:?} {wrap:?} at {p:?}: got {got}, Mitsuba {want:?}"
        );
    }
}

// The rows below are what tests/data/volumes/mitsuba_values.py printed: Mitsuba 3.9.1, variant
// scalar_rgb, `mi.load_dict({'type': 'gridvolume', 'filename': <the file>, <the properties>})`
// with the default identity to_world, each row (world point, `vol.eval(it)`) for an
// `it = mi.Interaction3f()` with `it.p` the point (floats with 9 significant digits).

const OUTSIDE: [[f32; 3]; 4] = [
    [-0.200000003, 0.5, 1.29999995],
    [1.10000002, -0.0500000007, 0.5],
    [2.29999995, 0.400000006, -0.699999988],
    [-1.37, 0.610000014, 0.519999981],
];

#[test]
fn smoke_matches_mitsuba_trilinear_and_nearest() {
    let smoke = read_vol(&data("smoke.vol")).unwrap();
    // smoke.vol, defaults (filter_type trilinear, wrap_mode clamp); Mitsuba's max() is 1.
    #[rustfmt::skip]
    let trilinear = [
        ([0.5, 0.5, 0.5], [0.89002049; 3]),
        ([0.0, 0.0, 0.0], [0.0; 3]),
        ([1.0, 1.0, 1.0], [0.0021156033; 3]),
        ([0.123000003, 0.456, 0.788999975], [0.0227147564; 3]),
        ([0.899999976, 0.100000001, 0.349999994], [0.0359197892; 3]),
        ([0.370000005, 0.610000014, 0.519999981], [0.567878187; 3]),
        ([0.25, 0.75, 0.5], [0.282160431; 3]),
        ([0.145833328, 0.3125, 0.479166657], [0.179348364; 3]),
        ([0.0199999996, 0.980000019, 0.5], [0.000553432095; 3]),
        ([0.5, 0.300000012, 0.449999988], [0.863810897; 3]),
        (OUTSIDE[0], [0.0; 3]),
        (OUTSIDE[1], [0.0140956482; 3]),
        (OUTSIDE[2], [0.00201835483; 3]),
        (OUTSIDE[3], [0.0675720125; 3]),
    ];
    check_mitsuba(&smoke, FilterType::Trilinear, WrapMode::Clamp, &trilinear);
    for (p, want) in trilinear {
        assert_eq!(smoke.eval(Vec3::from(p)), Vec3::from(want), "eval at {p:?}");
    }
    // filter_type nearest.
    #[rustfmt::skip]
    let nearest = [
        ([0.5, 0.5, 0.5], [0.896770358; 3]),
        ([0.0, 0.0, 0.0], [0.0; 3]),
        ([1.0, 1.0, 1.0], [0.0021156033; 3]),
        ([0.123000003, 0.456, 0.788999975], [0.0229544379; 3]),
        ([0.899999976, 0.100000001, 0.349999994], [0.0395498797; 3]),
        ([0.370000005, 0.610000014, 0.519999981], [0.558876336; 3]),
        ([0.25, 0.75, 0.5], [0.243019328; 3]),
        ([0.145833328, 0.3125, 0.479166657], [0.179348364; 3]),
        ([0.0199999996, 0.980000019, 0.5], [0.000117942007; 3]),
        ([0.5, 0.300000012, 0.449999988], [0.871011257; 3]),
        (OUTSIDE[0], [0.0; 3]),
        (OUTSIDE[1], [0.0142923091; 3]),
        (OUTSIDE[2], [0.00185057882; 3]),
        (OUTSIDE[3], [0.0656215549; 3]),
    ];
    check_mitsuba(&smoke, FilterType::Nearest, WrapMode::Clamp, &nearest);
    for (p, want) in nearest {
        assert_eq!(
            smoke.eval_nearest(Vec3::from(p)),
            Vec3::from(want),
            "nearest at {p:?}"
        );
    }
    // At a cell's centre (cell (3, 7, 11)) trilinear and nearest agree with the cell.
    assert_close(
        smoke.cell(3, 7, 11),
        Vec3::splat(0.179348364),
        0.0,
        "cell (3, 7, 11)",
    );
}

#[test]
fn smoke_matches_mitsuba_wrap_modes() {
    let smoke = read_vol(&data("smoke.vol")).unwrap();
    // wrap_mode repeat, then mirror (trilinear), then mirror with filter_type nearest.
    #[rustfmt::skip]
    let repeat = [
        (OUTSIDE[0], [0.158418387; 3]),
        (OUTSIDE[1], [0.0152688213; 3]),
        (OUTSIDE[2], [0.326691985; 3]),
        (OUTSIDE[3], [0.806047201; 3]),
    ];
    #[rustfmt::skip]
    let mirror = [
        (OUTSIDE[0], [0.11641819; 3]),
        (OUTSIDE[1], [0.0358165316; 3]),
        (OUTSIDE[2], [0.273591846; 3]),
        (OUTSIDE[3], [0.806047201; 3]),
    ];
    #[rustfmt::skip]
    let mirror_nearest = [
        (OUTSIDE[0], [0.115863033; 3]),
        (OUTSIDE[1], [0.0400663093; 3]),
        (OUTSIDE[2], [0.325088561; 3]),
        (OUTSIDE[3], [0.816236734; 3]),
    ];
    check_mitsuba(&smoke, FilterType::Trilinear, WrapMode::Repeat, &repeat);
    check_mitsuba(&smoke, FilterType::Trilinear, WrapMode::Mirror, &mirror);
    check_mitsuba(
        &smoke,
        FilterType::Nearest,
        WrapMode::Mirror,
        &mirror_nearest,
    );
}

#[test]
fn smoke_matches_mitsuba_with_use_grid_bbox() {
    // use_grid_bbox true: the file's box [-1, 1]^3 is mapped onto the unit cube before the
    // lookup; without it (the default, above) the box is ignored, and Mitsuba's value at the
    // world origin here is its value at (0.5, 0.5, 0.5) there.
    let smoke = read_vol(&data("smoke.vol")).unwrap();
    let m = smoke.bbox_transform().unwrap();
    #[rustfmt::skip]
    let rows: [([f32; 3], [f32; 3]); 4] = [
        ([0.0, 0.0, 0.0], [0.89002043; 3]),
        ([-0.5, 0.25, 0.100000001], [0.357367516; 3]),
        ([0.800000012, -0.899999976, 0.300000012], [0.0195773989; 3]),
        ([-1.0, 1.0, -1.0], [0.000637232733; 3]),
    ];
    for (world, want) in rows {
        let got = smoke.eval(m.transform_point3(Vec3::from(world)));
        assert_close(
            got,
            Vec3::from(want),
            4e-7,
            &format!("use_grid_bbox at {world:?}"),
        );
    }
    // Ignoring the box is not the same: the origin of the world is a corner of the unit cube.
    assert_close(
        smoke.eval(Vec3::ZERO),
        Vec3::ZERO,
        0.0,
        "no bbox at the origin",
    );
}

#[test]
fn ramp_and_rgb_match_mitsuba() {
    let ramp = read_vol(&data("ramp.vol")).unwrap();
    // ramp.vol, defaults; Mitsuba's max() is 1.5.
    #[rustfmt::skip]
    let rows = [
        ([-0.5, 0.300000012, 0.800000012], [0.5; 3]),
        ([0.0, 0.300000012, 0.800000012], [0.5; 3]),
        ([0.200000003, 0.300000012, 0.800000012], [0.5; 3]),
        ([0.25, 0.300000012, 0.800000012], [0.5; 3]),
        ([0.400000006, 0.300000012, 0.800000012], [0.799999952; 3]),
        ([0.5, 0.300000012, 0.800000012], [0.999999881; 3]),
        ([0.699999988, 0.300000012, 0.800000012], [1.39999986; 3]),
        ([0.75, 0.300000012, 0.800000012], [1.49999988; 3]),
        ([1.0, 0.300000012, 0.800000012], [1.5; 3]),
    ];
    check_mitsuba(&ramp, FilterType::Trilinear, WrapMode::Clamp, &rows);
    // rgb.vol, defaults: 3 channels come back as they are in scalar_rgb; Mitsuba's max() is
    // 1.57500005 (the largest value of any channel).
    let rgb = read_vol(&data("rgb.vol")).unwrap();
    #[rustfmt::skip]
    let rows = [
        ([0.5, 0.5, 0.5], [0.8125, 0.912500024, 1.01250005]),
        ([0.0, 0.0, 0.0], [0.25, 0.349999964, 0.450000018]),
        ([1.0, 1.0, 1.0], [1.375, 1.47500014, 1.57499993]),
        ([0.123000003, 0.456, 0.788999975], [0.58099997, 0.680999935, 0.781000018]),
        ([0.899999976, 0.100000001, 0.349999994], [0.774999976, 0.875, 0.975000024]),
        ([0.370000005, 0.610000014, 0.519999981], [0.829999983, 0.930000067, 1.02999997]),
        ([0.25, 0.75, 0.5], [0.875, 0.975000024, 1.07500005]),
        ([0.145833328, 0.3125, 0.479166657], [0.369791687, 0.469791651, 0.569791615]),
        ([0.0199999996, 0.980000019, 0.5], [0.8125, 0.912500024, 1.01250005]),
        ([0.5, 0.300000012, 0.449999988], [0.600000024, 0.700000048, 0.800000012]),
    ];
    check_mitsuba(&rgb, FilterType::Trilinear, WrapMode::Clamp, &rows);
    assert_eq!(rgb.max(), 1.57500005);
}
