//! `hppm compare` (issue 6): the error metrics against hand-computed values, masks, the snapshot
//! schedule and slope fit, the peer CSV, and a two-graph comparison on lavapipe through the
//! binary, as a user runs it.

use std::path::{Path, PathBuf};
use std::process::Command;

use hppm::app::compare::{log_log_slope, parse_peer_csv, read_mask, snapshot_times};
use hppm::image::{Image, Provenance};

fn image(width: u32, height: u32, pixels: Vec<[f32; 3]>) -> Image {
    Image {
        width,
        height,
        pixels,
    }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * b.abs().max(1.0)
}

/// Two pixels, six channel errors: by hand, relMSE = (1/0.01 + 1/1.01 + 0 + 4/4.01 + 0 + 0)/6,
/// RMSE = sqrt((1 + 1 + 0 + 4 + 0 + 0)/6) = 1, MAE = (1 + 1 + 0 + 2 + 0 + 0)/6.
#[test]
fn metrics_match_hand_computed_values() {
    let reference = image(2, 1, vec![[0.0, 1.0, 1.0], [2.0, 3.0, 0.5]]);
    let x = image(2, 1, vec![[1.0, 2.0, 1.0], [4.0, 3.0, 0.5]]);
    let m = x.metrics_where(&reference, |_| true).expect("same size");
    assert!(
        close(m.relmse, (100.0 + 1.0 / 1.01 + 4.0 / 4.01) / 6.0),
        "{m:?}"
    );
    assert!(close(m.rmse, 1.0), "{m:?}");
    assert!(close(m.mae, 4.0 / 6.0), "{m:?}");
    assert_eq!(m.pixels, 2);
    assert!(close(x.relmse(&reference).expect("same size"), m.relmse));

    // Only the second pixel: (0 + ... ) over three channels.
    let second = x.metrics_where(&reference, |i| i == 1).expect("same size");
    assert!(close(second.relmse, 4.0 / 4.01 / 3.0), "{second:?}");
    assert!(close(second.rmse, (4.0f64 / 3.0).sqrt()), "{second:?}");
    assert!(close(second.mae, 2.0 / 3.0), "{second:?}");
    assert_eq!(second.pixels, 1);

    let other = image(1, 2, vec![[0.0; 3]; 2]);
    assert!(x.metrics_where(&other, |_| true).is_err(), "sizes differ");
}

#[test]
fn snapshots_are_log_spaced_and_slopes_fit_power_laws() {
    let t = snapshot_times(60.0, 12);
    assert_eq!(t.len(), 12);
    assert!(close(t[0], 0.6) && close(t[11], 60.0), "{t:?}");
    for w in t.windows(2) {
        assert!(close(w[1] / w[0], 100f64.powf(1.0 / 11.0)), "{t:?}");
    }
    assert_eq!(snapshot_times(5.0, 1), vec![5.0]);

    let power: Vec<(f64, f64)> = [0.5, 1.0, 4.0, 30.0]
        .iter()
        .map(|&s: &f64| (s, 0.2 * s.powf(-0.8)))
        .collect();
    assert!(close(log_log_slope(&power).expect("fit"), -0.8));
    assert_eq!(log_log_slope(&[(1.0, 1.0)]), None);
    assert_eq!(
        log_log_slope(&[(2.0, 1.0), (2.0, 3.0)]),
        None,
        "no spread in time"
    );
}

#[test]
fn peer_csv_rows_and_errors_with_their_line() {
    let path = Path::new("peer.csv");
    let rows = parse_peer_csv(
        path,
        "# measured elsewhere\nseconds,relmse,label\n0.5, 0.1, Mitsuba\n# a comment\n\n2,0.03\n",
    )
    .expect("valid");
    assert_eq!(rows.len(), 2);
    assert_eq!(rows[0].label, "Mitsuba");
    assert_eq!(rows[1].label, "peer");
    assert!(close(rows[1].seconds, 2.0) && close(rows[1].relmse, 0.03));
    let err = parse_peer_csv(path, "seconds,relmse,label\n1,0.1,a\n1,minus,a\n")
        .expect_err("bad number")
        .to_string();
    assert!(err.contains("peer.csv:3:"), "{err}");
    let err = parse_peer_csv(path, "-1,0.1,a\n")
        .expect_err("negative")
        .to_string();
    assert!(err.contains("peer.csv:1:"), "{err}");
}

fn temp_dir(label: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hppm-compare-{label}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// The glass furnace's exact image (every pixel 2) is the reference, so the test knows the
/// answer without a stored EXR: pt and the hybrid, 1.5 s each, 4 snapshots, a mask, a peer.
#[test]
fn two_graph_compare_writes_csv_images_and_plot() {
    let dir = temp_dir("run");
    let (w, h) = (16u32, 12u32);
    let reference = dir.join("reference.exr");
    image(w, h, vec![[2.0; 3]; (w * h) as usize])
        .write(&reference, &Provenance::default())
        .expect("write reference");
    // Measure the left half only.
    let mask = dir.join("mask.exr");
    let mask_pixels = (0..w * h)
        .map(|i| if i % w < w / 2 { [0.0; 3] } else { [1.0; 3] })
        .collect();
    image(w, h, mask_pixels)
        .write(&mask, &Provenance::default())
        .expect("write mask");
    let peer = dir.join("peer.csv");
    std::fs::write(&peer, "seconds,relmse,label\n0.1,0.5,other\n1,0.05,other\n").expect("peer");
    let out = dir.join("out");
    let arg = |p: &Path| p.to_string_lossy().into_owned();
    let run = Command::new(env!("CARGO_BIN_EXE_hppm"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args([
            "compare",
            "tests/data/scenes/glass_furnace.ron",
            "--reference",
            &arg(&reference),
            "--graph",
            "graphs/pt.ron",
            "--graph",
            "graphs/hybrid.ron",
            "--time",
            "1.5",
            "--snapshots",
            "4",
            "--size",
            "16x12",
            "--mask",
            &arg(&mask),
            "--peer",
            &arg(&peer),
            "--profile",
            "--out",
            &arg(&out),
        ])
        .output()
        .expect("run hppm");
    let stdout = String::from_utf8_lossy(&run.stdout);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(stdout.contains("slope"), "{stdout}");
    assert!(
        stdout.contains("GPU ms") && stdout.contains("path_trace"),
        "{stdout}"
    );

    let csv = std::fs::read_to_string(out.join("errors.csv")).expect("errors.csv");
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some(
            "graph,snapshot,seconds,iterations,spp,photons,relmse,rmse,mae,estimated_relmse,\
             estimated_variance,estimated_bias"
        )
    );
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert_eq!(rows.len(), 8, "one row per graph and snapshot:\n{csv}");
    for graph in ["pt", "hybrid"] {
        let mine: Vec<&Vec<String>> = rows.iter().filter(|r| r[0] == graph).collect();
        assert_eq!(mine.len(), 4, "{graph}:\n{csv}");
        let seconds: Vec<f64> = mine
            .iter()
            .map(|r| r[2].parse().expect("seconds"))
            .collect();
        assert!(
            seconds.windows(2).all(|w| w[1] > w[0]),
            "{graph}: {seconds:?}"
        );
        let index: Vec<&str> = mine.iter().map(|r| r[1].as_str()).collect();
        assert_eq!(index, ["0", "1", "2", "3"]);
        for r in &mine {
            let relmse: f64 = r[6].parse().expect("relmse");
            let rmse: f64 = r[7].parse().expect("rmse");
            // Against a constant 2: relMSE = MSE / 4.01, whatever the image.
            assert!(
                close(relmse, rmse * rmse / 4.01)
                    || (relmse - rmse * rmse / 4.01).abs() < 1e-6 * relmse
            );
            // The estimate, from two iterations on (docs/error-estimate.md).
            let iterations: u64 = r[3].parse().expect("iterations");
            assert_eq!(r[9].is_empty(), iterations < 2, "{r:?}");
        }
        let final_image = Image::read_exr(&out.join(format!("{graph}.exr"))).expect("final image");
        assert_eq!((final_image.width, final_image.height), (w, h));
    }
    let photons: Vec<&str> = rows
        .iter()
        .filter(|r| r[0] == "hybrid")
        .map(|r| r[5].as_str())
        .collect();
    assert!(
        photons.iter().all(|p| *p != "0"),
        "the hybrid emits photons: {photons:?}"
    );

    let png = std::fs::File::open(out.join("errors.png")).expect("errors.png");
    let info = png::Decoder::new(std::io::BufReader::new(png))
        .read_info()
        .expect("a valid PNG");
    assert_eq!((info.info().width, info.info().height), (820, 560));

    let profile = std::fs::read_to_string(out.join("profile.csv")).expect("profile.csv");
    assert!(
        profile
            .lines()
            .any(|l| l.starts_with("hybrid,photons,photon_trace,")),
        "{profile}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The mask keeps its zero pixels; a wrong size or a mask that keeps nothing is refused.
#[test]
fn a_mask_keeps_its_zero_pixels() {
    let dir = temp_dir("mask");
    let path = dir.join("mask.exr");
    image(2, 2, vec![[0.0; 3], [1.0; 3], [0.0; 3], [0.0, 0.5, 0.0]])
        .write(&path, &Provenance::default())
        .expect("write mask");
    let keep = read_mask(&path, 2, 2).expect("mask");
    assert_eq!(keep, [true, false, true, false]);
    let reference = image(2, 2, vec![[1.0; 3]; 4]);
    let x = image(2, 2, vec![[1.0; 3], [5.0; 3], [1.0; 3], [9.0; 3]]);
    let m = x.metrics_where(&reference, |i| keep[i]).expect("same size");
    assert_eq!((m.relmse, m.rmse, m.mae, m.pixels), (0.0, 0.0, 0.0, 2));

    let err = read_mask(&path, 4, 1).expect_err("size").to_string();
    assert!(err.contains("mask.exr") && err.contains("2x2"), "{err}");
    image(1, 1, vec![[1.0; 3]])
        .write(&path, &Provenance::default())
        .expect("write mask");
    let err = read_mask(&path, 1, 1)
        .expect_err("keeps nothing")
        .to_string();
    assert!(err.contains("no pixel"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Without `--reference`, compare still reports error against time: the render's own estimate,
/// with the measured columns empty, and a plot of it.
#[test]
fn compare_without_a_reference_reports_the_estimate() {
    let dir = std::env::temp_dir().join(format!("hppm-compare-estimate-{}", std::process::id()));
    let out = dir.join("out");
    let run = Command::new(env!("CARGO_BIN_EXE_hppm"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args([
            "compare",
            "scenes/cornell_box.ron",
            "--graph",
            "graphs/pt.ron",
            "--time",
            "1",
            "--snapshots",
            "3",
            "--size",
            "16x12",
            "--out",
        ])
        .arg(&out)
        .output()
        .expect("run hppm");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let csv = std::fs::read_to_string(out.join("errors.csv")).expect("errors.csv");
    let last: Vec<&str> = csv.lines().last().expect("a row").split(',').collect();
    assert!(
        last[6].is_empty() && last[7].is_empty(),
        "no reference, no measured error: {csv}"
    );
    let estimated: f64 = last[9].parse().expect("an estimate in the last row");
    assert!(estimated > 0.0 && estimated.is_finite(), "{csv}");
    assert!(out.join("errors.png").exists());
    let _ = std::fs::remove_dir_all(&dir);
}
