//! Drives a validated graph over a scene.

/// Placeholder until the scene upload lands.
pub struct SceneResources {}
