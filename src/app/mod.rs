//! The application on top of the library: render jobs from files to files, `hppm compare`, the
//! live view in tev and, with the command line, `hppm bench`, plots and profile tables. The CLI
//! (src/cli.rs) and Python call these; the render itself is [`crate::render`].

#[cfg(feature = "cli")]
pub mod bench;
#[cfg(feature = "cli")]
pub mod bench_gather;
#[cfg(feature = "cli")]
pub mod bench_hybrid;
#[cfg(feature = "cli")]
pub mod bench_seed;
pub mod compare;
pub mod job;
#[cfg(feature = "cli")]
pub mod plot;
pub mod tev;
