//! The render graph: RON schema, validation, scheduling.

pub mod pass;

/// Placeholder until graph validation lands.
#[derive(Debug, thiserror::Error)]
#[error("graph errors")]
pub struct GraphErrors;

// TEMPORARY stub until graph-work merges.
pub struct Edge {
    pub from_node: usize,
    pub from_slot: &'static str,
    pub to_node: usize,
    pub to_slot: &'static str,
}
pub struct ValidNode {
    pub name: String,
    pub pass: Box<dyn pass::Pass>,
}
pub struct ValidGraph {
    pub nodes: Vec<ValidNode>,
    pub edges: Vec<Edge>,
    pub order: Vec<usize>,
    pub output: (usize, &'static str),
    pub warnings: Vec<String>,
}
impl ValidGraph {
    pub fn inputs_of(&self, node: usize) -> impl Iterator<Item = &Edge> {
        self.edges.iter().filter(move |e| e.to_node == node)
    }
    pub fn schedule_text(&self) -> String {
        todo!()
    }
    pub fn to_dot(&self) -> String {
        todo!()
    }
}
pub fn load_graph(
    _p: &std::path::Path,
    _r: &'static [pass::PassKind],
) -> Result<ValidGraph, GraphErrors> {
    let node = ValidNode {
        name: "camera".into(),
        pass: (crate::passes::registry()[0].construct)("()").map_err(|_| GraphErrors)?,
    };
    Ok(ValidGraph {
        nodes: vec![node],
        edges: vec![],
        order: vec![0],
        output: (0, "radiance"),
        warnings: vec![],
    })
}
