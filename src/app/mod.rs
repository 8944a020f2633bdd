//! The application on top of the library: the render loop and its budgets, `hppm compare`,
//! `hppm bench`, plots and profile tables. The CLI (src/cli.rs) calls these.

pub mod adaptive;
pub mod bench;
pub mod bench_gather;
pub mod bench_hybrid;
pub mod bench_seed;
pub mod compare;
pub mod error_estimate;
pub mod job;
#[cfg(feature = "cli")]
pub mod plot;
pub mod render;
pub mod state;
pub mod tev;
