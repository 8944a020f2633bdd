//! The library's render: a [`Renderer`] runs a validated graph over a scene until a [`Budget`] is
//! met, estimates its own error as it goes ([`error_estimate`]), samples adaptively
//! ([`adaptive`]), and saves or resumes its state and merges shards ([`state`]). The command line,
//! Python and host programs all render through it.

pub mod adaptive;
pub mod auto;
mod budget;
pub mod error_estimate;
pub mod fingerprint;
mod renderer;
pub mod state;

pub use budget::{Budget, BudgetField};
pub use renderer::{ErrorReport, NodeTime, Renderer, RendererBuilder, RunSummary, Stop, Term};
