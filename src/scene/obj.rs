//! TODO
use super::*;
pub fn load_scene(_p: &Path) -> Result<Scene, SceneError> {
    todo!()
}
