//! TODO (temporary stub, replaced by the scene-work branch)
use glam::Vec3;
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable, PartialEq)]
pub struct BvhNode {
    pub min: [f32; 3],
    pub left_or_first: u32,
    pub max: [f32; 3],
    pub count: u32,
}
#[derive(Clone, Copy, Debug)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    pub indices: Vec<u32>,
}
pub fn build_sah(_boxes: &[Aabb], _max_leaf_size: usize) -> Bvh {
    todo!()
}
pub fn scene_boxes(_scene: &super::Scene) -> Vec<Aabb> {
    todo!()
}
impl super::Scene {
    pub fn bounds(&self) -> (Vec3, Vec3) {
        todo!()
    }
}
