//! Every light path counted once, checked on the graph as a whole. Passes name classes of light
//! paths (a bit each; the classes and what "all paths" means are the passes' business, see
//! `passes::transport`) and say which classes each of their image outputs carries, given what
//! their inputs carry; a node that says nothing carries the union of its inputs. The graph
//! then follows the classes from the sources to its output and refuses a node where two inputs
//! carry the same class (that light would be counted twice), an output that lacks a class
//! (counted by nobody), and sources that count paths to different depths or draw the line
//! between specular and diffuse lobes at different roughnesses.

use std::collections::{HashMap, HashSet};

use super::{GraphError, GraphErrors, ValidGraph};

/// The longest path a source counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Depth {
    /// The source sets no rule of its own (a pass-through).
    Any,
    /// The scene's integrator setting.
    Scene,
    /// This many segments.
    Segments(u32),
}

impl std::fmt::Display for Depth {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Depth::Any => write!(f, "any depth"),
            Depth::Scene => write!(f, "the scene's max_depth"),
            Depth::Segments(n) => write!(f, "max_depth {n}"),
        }
    }
}

/// The roughness below which a source counts a microfacet lobe as specular (`glossy_threshold`,
/// docs/design.md section 1), and the node that says so. Sources that split paths into classes at
/// specular vertices must agree on it: a lobe one of them calls specular and the other not is
/// counted by both or by neither.
#[derive(Debug, Clone, Copy)]
pub struct SpecularRule {
    pub threshold: f32,
    node: usize,
}

impl PartialEq for SpecularRule {
    fn eq(&self, other: &Self) -> bool {
        self.threshold.to_bits() == other.threshold.to_bits() && self.node == other.node
    }
}

impl Eq for SpecularRule {}

impl SpecularRule {
    fn agrees(&self, other: &SpecularRule) -> bool {
        self.threshold.to_bits() == other.threshold.to_bits()
    }
}

/// Which path classes a slot carries, to what depth, and which node counts each class.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Transport {
    pub paths: u32,
    pub depth: Depth,
    /// Where the sources draw the line between specular and glossy lobes; `None` when no source
    /// draws one (a pass-through, or a source whose classes do not depend on it).
    pub specular: Option<SpecularRule>,
    /// (classes, node) for every source that contributes.
    sources: Vec<(u32, usize)>,
    /// Classes that [`Transport::and`] found on both sides: counted twice.
    twice: u32,
    /// Two specular rules that [`Transport::and`] found on its two sides, disagreeing (reported
    /// at the node that declared it, not passed on).
    specular_conflict: Option<(SpecularRule, SpecularRule)>,
}

impl Transport {
    /// Carries no light (hit points, trees).
    pub fn none() -> Self {
        Self {
            paths: 0,
            depth: Depth::Any,
            specular: None,
            sources: Vec::new(),
            twice: 0,
            specular_conflict: None,
        }
    }

    /// The same light under other class names: classes in `from` become `to` (a node that turns
    /// what it receives into another class, as a photon map looked up at other vertices does).
    pub fn relabel(&self, from: u32, to: u32) -> Self {
        let rename = |paths: u32| {
            if paths & from != 0 {
                (paths & !from) | to
            } else {
                paths
            }
        };
        Self {
            paths: rename(self.paths),
            depth: self.depth,
            specular: self.specular,
            sources: self.sources.iter().map(|&(p, n)| (rename(p), n)).collect(),
            twice: self.twice,
            specular_conflict: self.specular_conflict,
        }
    }

    /// This light and `other`'s in one output (a node that is a source and also passes on what
    /// an input carries). A class on both sides is counted twice, which the check reports.
    pub fn and(mut self, other: &Transport) -> Self {
        self.twice |= self.paths & other.paths;
        self.paths |= other.paths;
        self.sources.extend(other.sources.iter().copied());
        if self.depth == Depth::Any {
            self.depth = other.depth;
        }
        match (self.specular, other.specular) {
            (None, theirs) => self.specular = theirs,
            (Some(ours), Some(theirs)) if !ours.agrees(&theirs) => {
                self.specular_conflict = Some((ours, theirs));
            }
            _ => {}
        }
        self
    }
}

/// What a pass sees when asked which paths one of its outputs carries.
pub struct TransportCtx<'a> {
    node: usize,
    /// The transport of each connected input (previous-iteration inputs left out: state, not
    /// light of this iteration).
    pub inputs: HashMap<&'static str, Transport>,
    /// Output slots that feed a node or are the graph's output.
    pub consumed: &'a HashSet<&'static str>,
}

impl TransportCtx<'_> {
    /// This node as the source of `paths`, counted to `depth`.
    pub fn source(&self, paths: u32, depth: Depth) -> Transport {
        Transport {
            paths,
            depth,
            specular: None,
            sources: vec![(paths, self.node)],
            twice: 0,
            specular_conflict: None,
        }
    }

    /// As [`TransportCtx::source`], for a source whose classes count microfacet lobes below
    /// `threshold` as specular.
    pub fn source_specular_below(&self, paths: u32, depth: Depth, threshold: f32) -> Transport {
        let mut t = self.source(paths, depth);
        t.specular = Some(SpecularRule {
            threshold,
            node: self.node,
        });
        t
    }
}

/// Class names for messages: bit i is `names[i]`.
pub struct PathClasses<'a> {
    pub all: u32,
    pub names: &'a [&'a str],
}

impl PathClasses<'_> {
    fn describe(&self, paths: u32) -> String {
        let named: Vec<&str> = (0..32)
            .filter(|bit| paths & (1 << bit) != 0)
            .map(|bit| self.names.get(bit).copied().unwrap_or("unnamed paths"))
            .collect();
        named.join(", ")
    }
}

struct Walk<'g, 'c> {
    graph: &'g ValidGraph,
    classes: &'c PathClasses<'c>,
    memo: HashMap<(usize, &'static str), Transport>,
    errors: Vec<GraphError>,
}

impl Walk<'_, '_> {
    fn node_names(&self, sources: &[(u32, usize)], paths: u32) -> Vec<String> {
        let mut names: Vec<String> = sources
            .iter()
            .filter(|(p, _)| p & paths != 0)
            .map(|(_, n)| format!("\"{}\"", self.graph.nodes[*n].name))
            .collect();
        names.dedup();
        names
    }

    /// The union of `items` at `node`; a class in two of them, or two depths, is an error.
    fn union(&mut self, node: usize, items: Vec<(&'static str, Transport)>) -> Transport {
        let mut total = Transport::none();
        for (slot, t) in items {
            let twice = total.paths & t.paths;
            if twice != 0 {
                let mut sources = total.sources.clone();
                sources.extend(t.sources.iter().copied());
                let by = self.node_names(&sources, twice);
                self.error(
                    node,
                    format!(
                        "{} would be counted twice (by {}; the second reaches this node through \
                         \"{slot}\")",
                        self.classes.describe(twice),
                        by.join(" and ")
                    ),
                );
            }
            total.depth = match (total.depth, t.depth) {
                (Depth::Any, d) | (d, Depth::Any) => d,
                (a, b) if a == b => a,
                (a, b) => {
                    self.error(
                        node,
                        format!(
                            "its inputs count paths to different depths ({a} and {b}): give the \
                             camera and photon passes the same max_depth"
                        ),
                    );
                    a
                }
            };
            match (total.specular, t.specular) {
                (None, theirs) => total.specular = theirs,
                (Some(ours), Some(theirs)) if !ours.agrees(&theirs) => {
                    self.specular_error(node, ours, theirs);
                }
                _ => {}
            }
            total.paths |= t.paths;
            total.sources.extend(t.sources);
        }
        total
    }

    fn specular_error(&mut self, node: usize, a: SpecularRule, b: SpecularRule) {
        let name = |rule: SpecularRule| &self.graph.nodes[rule.node].name;
        let message = format!(
            "its inputs split paths at different glossy_threshold values (\"{}\": {}, \"{}\": \
             {}): a lobe with a roughness between them would be counted by both or by neither; \
             give both nodes the same glossy_threshold",
            name(a),
            a.threshold,
            name(b),
            b.threshold
        );
        self.error(node, message);
    }

    fn error(&mut self, node: usize, message: String) {
        let n = &self.graph.nodes[node];
        let error = GraphError {
            location: n.location.clone(),
            message: format!("node \"{}\" ({}): {message}", n.name, n.kind.name),
        };
        if !self.errors.contains(&error) {
            self.errors.push(error);
        }
    }

    fn transport(&mut self, node: usize, slot: &'static str) -> Transport {
        if let Some(t) = self.memo.get(&(node, slot)) {
            return t.clone();
        }
        let edges: Vec<_> = self
            .graph
            .inputs_of(node)
            .filter(|e| !e.previous_iteration)
            .cloned()
            .collect();
        let mut inputs = Vec::new();
        for e in edges {
            let t = self.transport(e.from_node, e.from_slot);
            inputs.push((e.to_slot, t));
        }
        let consumed = self.graph.consumed(node);
        let ctx = TransportCtx {
            node,
            inputs: inputs.iter().cloned().collect(),
            consumed: &consumed,
        };
        let declared = self.graph.nodes[node].pass.transport(slot, &ctx);
        let t = match declared {
            Some(t) => t,
            None => self.union(node, inputs),
        };
        if let Some((a, b)) = t.specular_conflict {
            self.specular_error(node, a, b);
        }
        if t.twice != 0 {
            let by = self.node_names(&t.sources, t.twice);
            self.error(
                node,
                format!(
                    "{} would be counted twice (by {})",
                    self.classes.describe(t.twice),
                    by.join(" and ")
                ),
            );
        }
        self.memo.insert((node, slot), t.clone());
        t
    }
}

impl ValidGraph {
    /// Checks that the output carries every class in `classes.all`, each counted once and all
    /// to one depth. Every problem is reported, at the node where it arises.
    pub fn check_transport(&self, classes: &PathClasses<'_>) -> Result<(), GraphErrors> {
        let mut walk = Walk {
            graph: self,
            classes,
            memo: HashMap::new(),
            errors: Vec::new(),
        };
        let (node, slot) = self.output;
        let out = walk.transport(node, slot);
        let missing = classes.all & !out.paths;
        if missing != 0 {
            walk.error(
                node,
                format!(
                    "its output \"{slot}\" lacks {}: no node counts that light (a camera pass \
                     leaves it to photon mapping, or stops its paths, with no photon pass and \
                     estimator adding it)",
                    classes.describe(missing)
                ),
            );
        }
        if walk.errors.is_empty() {
            Ok(())
        } else {
            Err(GraphErrors(walk.errors))
        }
    }
}
