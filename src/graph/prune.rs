//! Pruning: after validation, nodes whose needs the scene lacks are removed with their edges
//! (docs/design.md section 3). Removal cascades: a node loses its place when a required input came
//! from a removed node, or when everything it fed was removed. Optional inputs of the survivors
//! simply become unconnected (`resolve` without `caustic` is path tracing alone).

use super::ValidGraph;
use super::pass::{SceneNeed, SlotDir};
use crate::Error;

/// A node removed by pruning, and why.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pruned {
    pub node: String,
    pub kind: &'static str,
    pub reason: String,
}

impl std::fmt::Display for Pruned {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "pruned \"{}\" ({}): {}",
            self.node, self.kind, self.reason
        )
    }
}

impl ValidGraph {
    /// Removes the nodes the scene has no use for; `has` says which needs the scene meets.
    /// Returns what was removed, in schedule order. Fails when the output node itself goes.
    pub fn prune(&mut self, has: impl Fn(&SceneNeed) -> bool) -> Result<Vec<Pruned>, Error> {
        let n = self.nodes.len();
        let mut reason: Vec<Option<String>> = self
            .nodes
            .iter()
            .map(|node| {
                node.pass
                    .needs()
                    .iter()
                    .find(|need| !has(need))
                    .map(|need| format!("the scene has no {}", need.description))
            })
            .collect();
        loop {
            let mut changed = false;
            for i in 0..n {
                if reason[i].is_some() {
                    continue;
                }
                let lost_input = self.edges.iter().find(|e| {
                    e.to_node == i
                        && reason[e.from_node].is_some()
                        && self.nodes[i]
                            .kind
                            .slot(e.to_slot)
                            .is_some_and(|s| s.dir == SlotDir::In && !s.optional)
                });
                let feeds: Vec<usize> = self
                    .edges
                    .iter()
                    .filter(|e| e.from_node == i)
                    .map(|e| e.to_node)
                    .collect();
                let feeds_nothing_left = i != self.output.0
                    && !feeds.is_empty()
                    && feeds.iter().all(|&to| reason[to].is_some());
                if let Some(e) = lost_input {
                    reason[i] = Some(format!(
                        "its input \"{}\" came from pruned node \"{}\"",
                        e.to_slot, self.nodes[e.from_node].name
                    ));
                    changed = true;
                } else if feeds_nothing_left {
                    reason[i] = Some("everything it fed was pruned".to_string());
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
        if let Some(why) = &reason[self.output.0] {
            return Err(Error::Other(format!(
                "{}: the output node \"{}\" would be pruned ({why}); use a graph whose output \
                 does not depend on it",
                self.file.display(),
                self.nodes[self.output.0].name
            )));
        }
        let pruned: Vec<Pruned> = self
            .order
            .iter()
            .filter_map(|&i| {
                reason[i].as_ref().map(|why| Pruned {
                    node: self.nodes[i].name.clone(),
                    kind: self.nodes[i].kind.name,
                    reason: why.clone(),
                })
            })
            .collect();
        self.remove_nodes(|i| reason[i].is_some());
        Ok(pruned)
    }

    /// Drops the nodes for which `remove` holds, with their edges, renumbering the rest.
    fn remove_nodes(&mut self, remove: impl Fn(usize) -> bool) {
        let mut new_index = vec![usize::MAX; self.nodes.len()];
        let mut next = 0;
        for (i, slot) in new_index.iter_mut().enumerate() {
            if !remove(i) {
                *slot = next;
                next += 1;
            }
        }
        let nodes = std::mem::take(&mut self.nodes);
        self.nodes = nodes
            .into_iter()
            .enumerate()
            .filter(|(i, _)| !remove(*i))
            .map(|(_, node)| node)
            .collect();
        self.edges
            .retain(|e| !remove(e.from_node) && !remove(e.to_node));
        for e in &mut self.edges {
            e.from_node = new_index[e.from_node];
            e.to_node = new_index[e.to_node];
        }
        self.order = self
            .order
            .iter()
            .filter(|&&i| !remove(i))
            .map(|&i| new_index[i])
            .collect();
        self.output.0 = new_index[self.output.0];
    }
}
