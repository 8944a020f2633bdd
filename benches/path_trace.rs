//! `cargo bench`: the same measurement as `hppm bench` (rays/s and samples/s of `path_trace` on
//! the bundled Cornell scenes, after a warm-up), printed as a Markdown table. Set
//! HPPM_BENCH_WRITE=BENCHMARKS.md to append the table there.

use std::path::{Path, PathBuf};

fn locate(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

fn main() {
    let adapter = std::env::var("HPPM_TEST_ADAPTER").ok();
    let write = std::env::var_os("HPPM_BENCH_WRITE").map(PathBuf::from);
    if let Err(e) = hppm::app::bench::run(adapter.as_deref(), 32, write.as_deref(), locate) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
