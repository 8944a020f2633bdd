//! The render graph: a RON file of nodes (pass kinds with params) and edges between named slots,
//! validated as a whole (every problem reported at once, each with `file:line:col`) and
//! scheduled in topological order with petgraph.

pub mod bundled;
pub mod exec;
pub mod pass;
mod prune;
mod source_map;
pub mod transport;
mod validate;

use std::fmt;
use std::path::{Path, PathBuf};

use crate::error::Location;
use pass::{Pass, PassKind, SlotDir};

pub use prune::Pruned;
pub use validate::parse_graph;

/// One problem in a graph file.
#[derive(Debug, Clone, PartialEq)]
pub struct GraphError {
    pub location: Location,
    pub message: String,
}

impl fmt::Display for GraphError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.location, self.message)
    }
}

/// Every problem found in a graph file.
#[derive(Debug, Clone, PartialEq)]
pub struct GraphErrors(pub Vec<GraphError>);

impl fmt::Display for GraphErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for e in &self.0 {
            writeln!(f, "{e}")?;
        }
        let n = self.0.len();
        write!(f, "{n} error{} in graph", if n == 1 { "" } else { "s" })
    }
}

impl std::error::Error for GraphErrors {}

pub struct ValidNode {
    pub name: String,
    pub kind: &'static PassKind,
    pub pass: Box<dyn Pass>,
    /// The params text the pass was constructed from (`()` when the file gives none).
    pub params: String,
    pub location: Location,
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Edge {
    pub from_node: usize,
    pub from_slot: &'static str,
    pub to_node: usize,
    pub to_slot: &'static str,
    /// The input reads what the output held at the end of the previous iteration, so the edge
    /// does not order its two nodes.
    pub previous_iteration: bool,
}

/// A graph whose every node, edge and slot checked out, with its schedule.
pub struct ValidGraph {
    pub file: PathBuf,
    pub nodes: Vec<ValidNode>,
    pub edges: Vec<Edge>,
    /// Node indices in execution order.
    pub order: Vec<usize>,
    /// The node and slot whose resource is the rendered image.
    pub output: (usize, &'static str),
    /// Problems that do not stop a render (e.g. a node that feeds nothing).
    pub warnings: Vec<GraphError>,
}

impl std::fmt::Debug for ValidGraph {
    /// The file, each node as `name (kind) params`, and the output.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let nodes: Vec<String> = self
            .nodes
            .iter()
            .map(|n| format!("{} ({}) {}", n.name, n.kind.name, n.params))
            .collect();
        let (node, slot) = self.output;
        let output = format!("{}.{slot}", self.nodes.get(node).map_or("?", |n| &n.name));
        f.debug_struct("ValidGraph")
            .field("file", &self.file)
            .field("nodes", &nodes)
            .field("output", &output)
            .finish()
    }
}

impl ValidGraph {
    /// The same graph with every pass constructed anew from its params: a render that splits
    /// its image into tiles prepares one per tile.
    pub fn instance(&self) -> Result<ValidGraph, crate::Error> {
        let nodes = self
            .nodes
            .iter()
            .map(|n| {
                let pass = (n.kind.construct)(&n.params).map_err(|e| {
                    crate::Error::Other(format!("{}: node \"{}\": {e}", n.location, n.name))
                })?;
                Ok(ValidNode {
                    name: n.name.clone(),
                    kind: n.kind,
                    pass,
                    params: n.params.clone(),
                    location: n.location.clone(),
                })
            })
            .collect::<Result<Vec<_>, crate::Error>>()?;
        Ok(ValidGraph {
            file: self.file.clone(),
            nodes,
            edges: self.edges.clone(),
            order: self.order.clone(),
            output: self.output,
            warnings: self.warnings.clone(),
        })
    }

    pub fn inputs_of(&self, node: usize) -> impl Iterator<Item = &Edge> {
        self.edges.iter().filter(move |e| e.to_node == node)
    }

    /// Output slots of `node` that feed a node through an input that is not observe-only, and
    /// the graph's output slot if it is on `node`.
    pub fn consumed(&self, node: usize) -> std::collections::HashSet<&'static str> {
        self.edges
            .iter()
            .filter(|e| e.from_node == node)
            .filter(|e| {
                !self.nodes[e.to_node]
                    .kind
                    .slot(e.to_slot)
                    .is_some_and(|s| s.observe_only)
            })
            .map(|e| e.from_slot)
            .chain((self.output.0 == node).then_some(self.output.1))
            .collect()
    }

    fn slot_name(&self, node: usize, slot: &str) -> String {
        format!("{}.{slot}", self.nodes[node].name)
    }

    /// The schedule as numbered lines, with each node's connections.
    pub fn schedule_text(&self) -> String {
        let mut out = format!(
            "schedule of {} ({} node{}):\n",
            self.file.display(),
            self.nodes.len(),
            if self.nodes.len() == 1 { "" } else { "s" }
        );
        for (step, &i) in self.order.iter().enumerate() {
            let node = &self.nodes[i];
            out.push_str(&format!(
                "{:>3}. {} ({})\n",
                step + 1,
                node.name,
                node.kind.name
            ));
            for slot in node.kind.slots {
                let persistent = if slot.persistent { ", persistent" } else { "" };
                let line = match slot.dir {
                    SlotDir::In => {
                        let from = self
                            .inputs_of(i)
                            .find(|e| e.to_slot == slot.name)
                            .map_or("(unconnected)".to_string(), |e| {
                                self.slot_name(e.from_node, e.from_slot)
                            });
                        let previous = if slot.previous_iteration {
                            " (previous iteration)"
                        } else {
                            ""
                        };
                        format!("in  {} <- {from}{previous}", slot.name)
                    }
                    SlotDir::Out => format!("out {}", slot.name),
                };
                out.push_str(&format!(
                    "       {line} [{}{persistent}]\n",
                    slot.kind.name()
                ));
            }
        }
        out.push_str(&format!(
            "output: {}\n",
            self.slot_name(self.output.0, self.output.1)
        ));
        out
    }

    /// Graphviz: one box per node labelled with its kind, one arrow per edge labelled with its
    /// slots; the output slot is drawn as an extra node.
    pub fn to_dot(&self) -> String {
        let quote = |s: &str| s.replace('\\', "\\\\").replace('"', "\\\"");
        let mut out = String::from("digraph hppm {\n    rankdir=LR;\n    node [shape=box];\n");
        for (i, node) in self.nodes.iter().enumerate() {
            out.push_str(&format!(
                "    n{i} [label=\"{}\\n({})\"];\n",
                quote(&node.name),
                node.kind.name
            ));
        }
        for e in &self.edges {
            // State carried to the next iteration is drawn dashed and does not constrain rank.
            let style = if e.previous_iteration {
                ", style=dashed, constraint=false"
            } else {
                ""
            };
            out.push_str(&format!(
                "    n{} -> n{} [label=\"{} -> {}\"{style}];\n",
                e.from_node, e.to_node, e.from_slot, e.to_slot
            ));
        }
        out.push_str(&format!(
            "    output [shape=ellipse];\n    n{} -> output [label=\"{}\"];\n}}\n",
            self.output.0, self.output.1
        ));
        out
    }
}

/// Reads and validates a graph file against the pass kinds of a registry
/// (`hppm::passes::Registry` holds the built-in ones and a program's own).
pub fn load_graph(path: &Path, registry: &[&'static PassKind]) -> Result<ValidGraph, GraphErrors> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        GraphErrors(vec![GraphError {
            location: Location::new(path, 1, 1),
            message: format!("cannot read graph file: {e}"),
        }])
    })?;
    parse_graph(path, &text, registry)
}
