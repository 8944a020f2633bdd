//! The render graph: RON schema, validation, scheduling.

pub mod pass;

/// Placeholder until graph validation lands.
#[derive(Debug, thiserror::Error)]
#[error("graph errors")]
pub struct GraphErrors;
