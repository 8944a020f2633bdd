//! From RON text to a `ValidGraph`: parse, resolve pass kinds, construct nodes from their params,
//! connect slots, check everything (collecting every problem), find cycles and schedule.

use std::collections::{BTreeSet, HashMap};
use std::ops::Range;
use std::path::Path;

use petgraph::algo::tarjan_scc;
use petgraph::graph::{DiGraph, NodeIndex};
use petgraph::visit::EdgeRef;
use serde::Deserialize;

use super::pass::{IMAGE, PassKind, SlotDecl, SlotDir};
use super::source_map::{self, NodeSpans, SourceMap};
use super::{Edge, GraphError, GraphErrors, ValidGraph, ValidNode};
use crate::error::{Location, edit_distance};

const VERSION: u32 = 1;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GraphFile {
    version: u32,
    nodes: Vec<NodeFile>,
    #[serde(default)]
    edges: Vec<String>,
    output: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct NodeFile {
    name: String,
    pass: String,
    // Parsed by the pass kind itself from the source text; here only skipped.
    #[serde(default)]
    #[allow(dead_code)]
    params: serde::de::IgnoredAny,
}

/// Collects problems with their locations.
struct Report<'a> {
    file: &'a Path,
    text: &'a str,
    errors: Vec<GraphError>,
}

impl Report<'_> {
    fn at(&self, offset: usize) -> Location {
        Location::from_offset(self.file, self.text, offset)
    }

    fn error(&mut self, offset: usize, message: impl Into<String>) {
        let location = self.at(offset);
        self.errors.push(GraphError {
            location,
            message: message.into(),
        });
    }
}

/// A node whose kind resolved (others are reported and left out of slot checks).
struct Resolved {
    index: usize,
    kind: &'static PassKind,
}

/// Parses and validates graph `text` read from `file`.
pub fn parse_graph(
    file: &Path,
    text: &str,
    registry: &[&'static PassKind],
) -> Result<ValidGraph, GraphErrors> {
    let parsed: GraphFile = ron::Options::default().from_str(text).map_err(|e| {
        GraphErrors(vec![GraphError {
            location: Location::new(file, e.span.start.line, e.span.start.col),
            message: e.code.to_string(),
        }])
    })?;
    let map = source_map::map(text);
    let mut report = Report {
        file,
        text,
        errors: Vec::new(),
    };
    if parsed.version != VERSION {
        let at = map.top("version").map_or(0, |f| f.value_span.start);
        report.error(
            at,
            format!(
                "version {} is not supported (expected {VERSION})",
                parsed.version
            ),
        );
    }
    let node_spans = |i: usize| map.nodes.get(i).cloned().unwrap_or_default();
    let mut nodes: Vec<Option<ValidNode>> = Vec::new();
    let mut resolved: Vec<Option<Resolved>> = Vec::new();
    let mut first_by_name: HashMap<&str, usize> = HashMap::new();
    for (i, node) in parsed.nodes.iter().enumerate() {
        let spans = node_spans(i);
        let name_at = spans
            .field("name")
            .map_or(spans.span.start, |f| f.value_span.start);
        if let Some(&first) = first_by_name.get(node.name.as_str()) {
            let first_line = report.at(node_spans(first).span.start).line;
            report.error(
                name_at,
                format!(
                    "duplicate node name \"{}\" (first defined on line {first_line})",
                    node.name
                ),
            );
        } else {
            first_by_name.insert(&node.name, i);
        }
        if node.name.is_empty() || node.name.contains(['.', ' ']) {
            report.error(
                name_at,
                format!(
                    "node name \"{}\" must be non-empty, without '.' or spaces",
                    node.name
                ),
            );
        }
        let kind = resolve_kind(&mut report, registry, &node.pass, &spans);
        let valid = kind.and_then(|kind| construct(&mut report, text, kind, node, &spans));
        resolved.push(kind.map(|kind| Resolved { index: i, kind }));
        nodes.push(valid.map(|pass| ValidNode {
            name: node.name.clone(),
            kind: pass.0,
            pass: pass.1,
            params: pass.2,
            location: report.at(spans.span.start),
        }));
    }
    let lookup = |name: &str| first_by_name.get(name).copied();
    let (edges, attempted) = connect(&mut report, &map, &parsed, &resolved, lookup);
    check_producers(&mut report, &parsed, &resolved, &attempted, &map);
    check_exclusive_and_required(&mut report, &parsed, &resolved, &edges, &map);
    let output = check_output(&mut report, &map, &parsed.output, &resolved, lookup);
    let graph = petgraph_of(parsed.nodes.len(), &edges);
    check_cycles(&mut report, &graph, &parsed, &edges);
    if !report.errors.is_empty() {
        return Err(GraphErrors(report.errors));
    }
    let (Some(output), Some(nodes)) = (output, nodes.into_iter().collect::<Option<Vec<_>>>())
    else {
        // Unreachable when no error was reported; kept as an error rather than a panic.
        return Err(GraphErrors(vec![GraphError {
            location: Location::new(file, 1, 1),
            message: "graph could not be built".into(),
        }]));
    };
    let edges: Vec<Edge> = edges.into_iter().map(|(e, _)| e).collect();
    let order = schedule(&graph);
    let warnings = unused_nodes(&graph, output.0, &nodes);
    Ok(ValidGraph {
        file: file.to_path_buf(),
        nodes,
        edges,
        order,
        output,
        warnings,
    })
}

fn resolve_kind(
    report: &mut Report,
    registry: &[&'static PassKind],
    pass: &str,
    spans: &NodeSpans,
) -> Option<&'static PassKind> {
    if let Some(kind) = registry.iter().find(|k| k.name == pass) {
        return Some(*kind);
    }
    let at = spans
        .field("pass")
        .map_or(spans.span.start, |f| f.value_span.start);
    let closest = registry
        .iter()
        .map(|k| (edit_distance(pass, k.name), k.name))
        .min()
        .filter(|(d, name)| *d <= 2.max(name.len() / 3));
    let hint = match closest {
        Some((_, name)) => format!(" (did you mean \"{name}\"?)"),
        None => {
            let known: Vec<_> = registry.iter().map(|k| k.name).collect();
            format!("; known kinds: {}", known.join(", "))
        }
    };
    report.error(at, format!("unknown pass kind \"{pass}\"{hint}"));
    None
}

/// Builds the pass from its params text; a params error is placed inside the params.
fn construct(
    report: &mut Report,
    text: &str,
    kind: &'static PassKind,
    node: &NodeFile,
    spans: &NodeSpans,
) -> Option<(&'static PassKind, Box<dyn super::pass::Pass>, String)> {
    let params = spans.field("params").map(|f| f.value_span.clone());
    let params_text = params.clone().and_then(|r| text.get(r)).unwrap_or("()");
    let params_text = if params_text.trim() == "None" {
        "()"
    } else {
        params_text
    };
    match (kind.construct)(params_text) {
        Ok(pass) => Some((kind, pass, params_text.to_string())),
        Err(e) => {
            let base = params.map_or(spans.span.start, |r| r.start);
            let (message, key) = describe_params_error(&e.code);
            let at = key
                .and_then(|key| spans.params_fields.iter().find(|f| f.key == key))
                .map(|f| f.key_span.start)
                .unwrap_or_else(|| {
                    base + offset_of(params_text, e.span.start.line, e.span.start.col)
                });
            report.error(
                at,
                format!("node \"{}\" ({}): {message}", node.name, kind.name),
            );
            None
        }
    }
}

/// A params error in the graph's words, and the param it is about (to place it).
fn describe_params_error(error: &ron::Error) -> (String, Option<String>) {
    match error {
        ron::Error::NoSuchStructField {
            expected, found, ..
        } => (
            format!(
                "unknown param \"{found}\"; known params: {}",
                expected.join(", ")
            ),
            Some(found.clone()),
        ),
        ron::Error::MissingStructField { field, .. } => {
            (format!("missing param \"{field}\""), None)
        }
        other => (format!("params: {other}"), None),
    }
}

/// Byte offset of 1-based (line, col) in `text`, clamped to the text.
fn offset_of(text: &str, line: usize, col: usize) -> usize {
    let mut offset = 0;
    for (i, l) in text.split_inclusive('\n').enumerate() {
        if i + 1 == line {
            return offset
                + l.char_indices()
                    .nth(col.saturating_sub(1))
                    .map_or(l.len(), |(b, _)| b);
        }
        offset += l.len();
    }
    text.len()
}

/// "node.slot" split in two.
fn split_slot(text: &str) -> Option<(&str, &str)> {
    let (node, slot) = text.trim().split_once('.')?;
    (!node.is_empty() && !slot.is_empty()).then_some((node.trim(), slot.trim()))
}

fn find_slot(
    report: &mut Report,
    at: usize,
    node: usize,
    slot: &str,
    resolved: &[Option<Resolved>],
    names: &[String],
) -> Option<&'static SlotDecl> {
    let kind = resolved.get(node)?.as_ref()?.kind;
    match kind.slot(slot) {
        Some(decl) => Some(decl),
        None => {
            let slots: Vec<_> = kind.slots.iter().map(|s| s.name).collect();
            report.error(
                at,
                format!(
                    "node \"{}\" ({}) has no slot \"{slot}\"; its slots: {}",
                    names[node],
                    kind.name,
                    slots.join(", ")
                ),
            );
            None
        }
    }
}

/// Inputs some edge was meant for, valid or not: they are not also "without producer".
type Attempted = BTreeSet<(usize, String)>;

/// Resolves every edge string; returns the valid edges with their source spans.
fn connect(
    report: &mut Report,
    map: &SourceMap,
    parsed: &GraphFile,
    resolved: &[Option<Resolved>],
    lookup: impl Fn(&str) -> Option<usize>,
) -> (Vec<(Edge, Range<usize>)>, Attempted) {
    let names: Vec<String> = parsed.nodes.iter().map(|n| n.name.clone()).collect();
    let mut edges: Vec<(Edge, Range<usize>)> = Vec::new();
    let mut attempted = Attempted::new();
    for (j, edge) in parsed.edges.iter().enumerate() {
        let span = map.edges.get(j).cloned().unwrap_or(0..0);
        let at = span.start;
        let Some((from, to)) = edge
            .split_once("->")
            .and_then(|(a, b)| Some((split_slot(a)?, split_slot(b)?)))
        else {
            report.error(
                at,
                format!("malformed edge \"{edge}\": expected \"node.slot -> node.slot\""),
            );
            continue;
        };
        if let Some(n) = lookup(to.0) {
            attempted.insert((n, to.1.to_string()));
        }
        let mut ends = Vec::new();
        for (node_name, slot) in [from, to] {
            match lookup(node_name) {
                Some(n) => ends.push((n, find_slot(report, at, n, slot, resolved, &names))),
                None => report.error(
                    at,
                    format!("edge \"{edge}\": no node named \"{node_name}\""),
                ),
            }
        }
        let [(from_node, Some(from_decl)), (to_node, Some(to_decl))] = ends[..] else {
            continue;
        };
        if from_decl.dir != SlotDir::Out {
            report.error(
                at,
                format!(
                    "edge \"{edge}\": \"{}.{}\" is an input; an edge must start at an output",
                    from.0, from.1
                ),
            );
            continue;
        }
        if to_decl.dir != SlotDir::In {
            report.error(
                at,
                format!(
                    "edge \"{edge}\": \"{}.{}\" is an output; an edge must end at an input",
                    to.0, to.1
                ),
            );
            continue;
        }
        if from_decl.kind != to_decl.kind {
            report.error(
                at,
                format!(
                    "slot kinds differ: \"{}.{}\" ({}) -> \"{}.{}\" ({})",
                    from.0,
                    from.1,
                    from_decl.kind.name(),
                    to.0,
                    to.1,
                    to_decl.kind.name()
                ),
            );
            continue;
        }
        if to_decl.previous_iteration && !from_decl.persistent {
            report.error(
                at,
                format!(
                    "edge \"{edge}\": \"{}.{}\" reads the previous iteration, but \"{}.{}\" does not persist across iterations",
                    to.0, to.1, from.0, from.1
                ),
            );
            continue;
        }
        if let Some((_, first)) = edges
            .iter()
            .find(|(e, _)| e.to_node == to_node && e.to_slot == to_decl.name)
        {
            let line = report.at(first.start).line;
            report.error(
                at,
                format!(
                    "input \"{}.{}\" is connected twice (first on line {line})",
                    to.0, to.1
                ),
            );
            continue;
        }
        let edge = Edge {
            from_node,
            from_slot: from_decl.name,
            to_node,
            to_slot: to_decl.name,
            previous_iteration: to_decl.previous_iteration,
        };
        edges.push((edge, span));
    }
    (edges, attempted)
}

fn check_producers(
    report: &mut Report,
    parsed: &GraphFile,
    resolved: &[Option<Resolved>],
    attempted: &Attempted,
    map: &SourceMap,
) {
    for r in resolved.iter().flatten() {
        for slot in r
            .kind
            .slots
            .iter()
            .filter(|s| s.dir == SlotDir::In && !s.optional)
        {
            if !attempted.contains(&(r.index, slot.name.to_string())) {
                let at = map.nodes.get(r.index).map_or(0, |n| n.span.start);
                report.error(
                    at,
                    format!(
                        "input \"{}.{}\" has no producer",
                        parsed.nodes[r.index].name, slot.name
                    ),
                );
            }
        }
    }
}

/// An output read through two exclusive inputs (two estimators on one set of hit points), and a
/// required output that feeds nothing.
fn check_exclusive_and_required(
    report: &mut Report,
    parsed: &GraphFile,
    resolved: &[Option<Resolved>],
    edges: &[(Edge, Range<usize>)],
    map: &SourceMap,
) {
    let slot_of = |node: usize, slot: &str| {
        resolved
            .get(node)
            .and_then(|r| r.as_ref())
            .and_then(|r| r.kind.slot(slot))
    };
    let mut exclusive_reader: HashMap<(usize, &str), &Edge> = HashMap::new();
    for (e, span) in edges {
        if !slot_of(e.to_node, e.to_slot).is_some_and(|s| s.exclusive) {
            continue;
        }
        match exclusive_reader.get(&(e.from_node, e.from_slot)) {
            None => {
                exclusive_reader.insert((e.from_node, e.from_slot), e);
            }
            Some(first) => {
                let name = |n: usize| parsed.nodes[n].name.as_str();
                report.error(
                    span.start,
                    format!(
                        "\"{}.{}\" already feeds \"{}.{}\"; \"{}.{}\" may have only one such \
                         reader (two estimators would shrink one set of radii)",
                        name(e.from_node),
                        e.from_slot,
                        name(first.to_node),
                        first.to_slot,
                        name(e.to_node),
                        e.to_slot
                    ),
                );
            }
        }
    }
    for r in resolved.iter().flatten() {
        for slot in r
            .kind
            .slots
            .iter()
            .filter(|s| s.dir == SlotDir::Out && s.required)
        {
            let feeds = edges
                .iter()
                .any(|(e, _)| e.from_node == r.index && e.from_slot == slot.name);
            if !feeds {
                let at = map.nodes.get(r.index).map_or(0, |n| n.span.start);
                report.error(
                    at,
                    format!(
                        "output \"{}.{}\" must feed a node (the {} it carries is needed back)",
                        parsed.nodes[r.index].name,
                        slot.name,
                        slot.kind.name()
                    ),
                );
            }
        }
    }
}

fn check_output(
    report: &mut Report,
    map: &SourceMap,
    output: &str,
    resolved: &[Option<Resolved>],
    lookup: impl Fn(&str) -> Option<usize>,
) -> Option<(usize, &'static str)> {
    let at = map.top("output").map_or(0, |f| f.value_span.start);
    let Some((node_name, slot)) = split_slot(output) else {
        report.error(at, format!("output \"{output}\": expected \"node.slot\""));
        return None;
    };
    let Some(node) = lookup(node_name) else {
        report.error(
            at,
            format!("output \"{output}\": no node named \"{node_name}\""),
        );
        return None;
    };
    let kind = resolved.get(node)?.as_ref()?.kind;
    match kind.slot(slot) {
        // The output becomes the image, so it must hold per-pixel radiance.
        Some(decl) if decl.dir == SlotDir::Out && decl.kind != IMAGE => {
            report.error(
                at,
                format!(
                    "output \"{output}\" carries {}, not radiance: the output must be an image",
                    decl.kind.name()
                ),
            );
            None
        }
        Some(decl) if decl.dir == SlotDir::Out => Some((node, decl.name)),
        Some(_) => {
            report.error(
                at,
                format!("output \"{output}\" is an input slot; the output must be an output slot"),
            );
            None
        }
        None => {
            let outs: Vec<_> = kind
                .slots
                .iter()
                .filter(|s| s.dir == SlotDir::Out)
                .map(|s| s.name)
                .collect();
            report.error(at, format!("output \"{output}\": node \"{node_name}\" ({}) has no output slot \"{slot}\"; its outputs: {}", kind.name, outs.join(", ")));
            None
        }
    }
}

fn petgraph_of(node_count: usize, edges: &[(Edge, Range<usize>)]) -> DiGraph<usize, usize> {
    let mut graph = DiGraph::new();
    for i in 0..node_count {
        graph.add_node(i);
    }
    // An edge that reads the previous iteration orders nothing within one.
    for (j, (e, _)) in edges
        .iter()
        .enumerate()
        .filter(|(_, (e, _))| !e.previous_iteration)
    {
        graph.add_edge(NodeIndex::new(e.from_node), NodeIndex::new(e.to_node), j);
    }
    graph
}

/// Reports each cycle once, naming its nodes in order, at one of its edges.
fn check_cycles(
    report: &mut Report,
    graph: &DiGraph<usize, usize>,
    parsed: &GraphFile,
    edges: &[(Edge, Range<usize>)],
) {
    for component in tarjan_scc(graph) {
        let members: BTreeSet<usize> = component.iter().map(|n| n.index()).collect();
        let Some(&start) = members.iter().next() else {
            continue;
        };
        let self_loop = graph
            .edges(NodeIndex::new(start))
            .any(|e| e.target().index() == start);
        if members.len() < 2 && !self_loop {
            continue;
        }
        // Walk the component from its first node until a node repeats: that is a cycle.
        let mut path = vec![start];
        let mut first_edge = None;
        while let Some(&here) = path.last() {
            let Some(step) = graph
                .edges(NodeIndex::new(here))
                .filter(|e| members.contains(&e.target().index()))
                .min_by_key(|e| e.target().index())
            else {
                break;
            };
            first_edge.get_or_insert(*step.weight());
            let next = step.target().index();
            if let Some(pos) = path.iter().position(|&n| n == next) {
                path.drain(..pos);
                path.push(next);
                break;
            }
            path.push(next);
        }
        let names: Vec<&str> = path
            .iter()
            .map(|&n| parsed.nodes[n].name.as_str())
            .collect();
        let at = first_edge
            .and_then(|j| edges.get(j))
            .map_or(0, |(_, span)| span.start);
        report.error(at, format!("cycle: {}", names.join(" -> ")));
    }
}

/// Topological order (Kahn), ties broken by file order so the schedule is deterministic.
fn schedule(graph: &DiGraph<usize, usize>) -> Vec<usize> {
    let mut indegree: Vec<usize> = graph
        .node_indices()
        .map(|n| {
            graph
                .neighbors_directed(n, petgraph::Direction::Incoming)
                .count()
        })
        .collect();
    let mut ready: BTreeSet<usize> = (0..indegree.len()).filter(|&i| indegree[i] == 0).collect();
    let mut order = Vec::with_capacity(indegree.len());
    while let Some(n) = ready.pop_first() {
        order.push(n);
        for e in graph.edges(NodeIndex::new(n)) {
            let t = e.target().index();
            indegree[t] -= 1;
            if indegree[t] == 0 {
                ready.insert(t);
            }
        }
    }
    order
}

/// Nodes from which the output cannot be reached do no useful work.
fn unused_nodes(
    graph: &DiGraph<usize, usize>,
    output: usize,
    nodes: &[ValidNode],
) -> Vec<GraphError> {
    let mut reaches = vec![false; nodes.len()];
    let mut stack = vec![output];
    while let Some(n) = stack.pop() {
        if std::mem::replace(&mut reaches[n], true) {
            continue;
        }
        stack.extend(
            graph
                .neighbors_directed(NodeIndex::new(n), petgraph::Direction::Incoming)
                .map(|m| m.index()),
        );
    }
    nodes
        .iter()
        .zip(reaches)
        .filter(|(_, r)| !r)
        .map(|(node, _)| GraphError {
            location: node.location.clone(),
            message: format!(
                "node \"{}\" ({}) does not contribute to the output",
                node.name, node.kind.name
            ),
        })
        .collect()
}
