//! hppm's command line with this crate's `tonemap` pass registered: `render`, `graph`, `info`,
//! `compare` and the rest know it.
//!
//!     cargo run -p custom_pass --release -- render scene.xml --graph examples/custom_pass/graphs/hybrid_tonemapped.ron --out image.png

fn main() -> std::process::ExitCode {
    hppm::cli::run(custom_pass::registry())
}
