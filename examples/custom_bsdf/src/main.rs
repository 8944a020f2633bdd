//! hppm's command line with this crate's `minnaert` BSDF registered: `render`, `check`,
//! `plugins` and the rest read scenes that use it.
//!
//!     cargo run -p custom_bsdf --release -- render examples/custom_bsdf/scenes/minnaert_glass.xml

fn main() -> std::process::ExitCode {
    hppm::cli::run(custom_bsdf::registry())
}
