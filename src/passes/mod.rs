//! The registry of pass kinds.
