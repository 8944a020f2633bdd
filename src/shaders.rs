//! WGSL composition with naga_oil.

/// Placeholder until the shader library lands.
pub struct ShaderLibrary {}
