//! Device and adapter choice, buffers with size checks, readback.

/// Placeholder until the GPU context lands.
pub struct GpuContext {}

#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error("{0}")]
    Other(String),
}
