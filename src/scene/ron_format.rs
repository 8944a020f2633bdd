//! TODO
use super::*;
pub fn load(_p: &Path) -> Result<Scene, SceneError> {
    todo!()
}
