//! Where things are in a graph file: the byte spans of each node, its fields and its params
//! keys, each edge and the output, read off the shared RON outline ([`crate::ron_span`]) so
//! that every validation error can name a line.

use std::ops::Range;

use crate::ron_span::{Group, Outline};

/// One `key: value` of a struct, with spans.
#[derive(Debug, Clone)]
pub struct Field {
    pub key: String,
    pub key_span: Range<usize>,
    pub value_span: Range<usize>,
}

/// Spans of one node of the `nodes` list.
#[derive(Debug, Clone, Default)]
pub struct NodeSpans {
    pub span: Range<usize>,
    pub fields: Vec<Field>,
    /// Keys inside `params: (...)`.
    pub params_fields: Vec<Field>,
}

impl NodeSpans {
    pub fn field(&self, key: &str) -> Option<&Field> {
        self.fields.iter().find(|f| f.key == key)
    }
}

#[derive(Debug, Clone, Default)]
pub struct SourceMap {
    pub top_fields: Vec<Field>,
    pub nodes: Vec<NodeSpans>,
    pub edges: Vec<Range<usize>>,
}

impl SourceMap {
    pub fn top(&self, key: &str) -> Option<&Field> {
        self.top_fields.iter().find(|f| f.key == key)
    }
}

/// The `key: value` items of a struct group (items without a key are left out).
fn fields(group: Group<'_>) -> Vec<Field> {
    group
        .items()
        .filter_map(|item| {
            let key = item.key()?;
            Some(Field {
                key: key.name.to_string(),
                key_span: key.span,
                value_span: item.value_span(),
            })
        })
        .collect()
}

/// The group of field `key`'s value in `group`, if it opens with `bracket`.
fn value_group<'a>(group: Group<'a>, key: &str, bracket: u8) -> Option<Group<'a>> {
    group.field(key)?.group().filter(|g| g.bracket() == bracket)
}

/// Records where the parts of a graph file are.
pub fn map(text: &str) -> SourceMap {
    let outline = Outline::new(text);
    let Some(top) = outline.value().filter(|g| g.bracket() == b'(') else {
        return SourceMap::default();
    };
    let nodes = value_group(top, "nodes", b'[').map_or_else(Vec::new, |list| {
        list.items()
            .map(|node| {
                // A node may be written `(..)` or `Node(..)`.
                let group = node.group().filter(|g| g.bracket() == b'(');
                NodeSpans {
                    span: node.span(),
                    fields: group.map(fields).unwrap_or_default(),
                    params_fields: group
                        .and_then(|g| value_group(g, "params", b'('))
                        .map(fields)
                        .unwrap_or_default(),
                }
            })
            .collect()
    });
    let edges = value_group(top, "edges", b'[').map_or_else(Vec::new, |list| {
        list.items().map(|edge| edge.span()).collect()
    });
    SourceMap {
        top_fields: fields(top),
        nodes,
        edges,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_nodes_params_and_edges() {
        let text = r#"// comment (with parens
(
    version: 1,
    nodes: [
        (name: "a", pass: "k", params: (x: Some((1, 2)), y: "s)")),
        Node(name: "b", pass: "k"),
    ],
    edges: ["a.out -> b.in", /* c */ "b.out -> a.in"],
    output: "b.out",
)"#;
        let map = map(text);
        assert_eq!(map.nodes.len(), 2);
        let a = &map.nodes[0];
        assert_eq!(&text[a.field("name").unwrap().value_span.clone()], "\"a\"");
        assert_eq!(
            &text[a.field("params").unwrap().value_span.clone()],
            "(x: Some((1, 2)), y: \"s)\")"
        );
        let keys: Vec<_> = a.params_fields.iter().map(|f| f.key.as_str()).collect();
        assert_eq!(keys, ["x", "y"]);
        assert_eq!(
            &text[map.nodes[1].field("pass").unwrap().value_span.clone()],
            "\"k\""
        );
        let edges: Vec<_> = map.edges.iter().map(|e| &text[e.clone()]).collect();
        assert_eq!(edges, ["\"a.out -> b.in\"", "\"b.out -> a.in\""]);
        assert_eq!(
            &text[map.top("output").unwrap().value_span.clone()],
            "\"b.out\""
        );
    }

    #[test]
    fn never_panics_on_truncations() {
        let text = r#"(version: 1, nodes: [(name: "a", pass: "k", params: (x: 1))], edges: ["a.b -> c.d"], output: "a.b")"#;
        for end in 0..text.len() {
            let _ = map(&text[..end]);
        }
        let _ = map("r#\"unterminated");
        let _ = map("\"\\");
    }

    /// What the old graph-only tokenizer got wrong: a nested block comment ended at its first
    /// `*/`, so ` c */` became tokens and the field after it was lost.
    #[test]
    fn a_nested_comment_and_a_raw_string_keep_the_fields_after_them() {
        let text = "(\n    version: 1,\n    nodes: [\n        /* a /* b */ c */ (name: \"a\", pass: \"k\", params: (s: r#\"x\") // \"#, y: 2)),\n    ],\n    /* a /* b */ c */ output: \"a.out\",\n)";
        let map = map(text);
        let a = &map.nodes[0];
        assert_eq!(
            &text[a.field("params").unwrap().value_span.clone()],
            "(s: r#\"x\") // \"#, y: 2)"
        );
        let keys: Vec<_> = a.params_fields.iter().map(|f| f.key.as_str()).collect();
        assert_eq!(keys, ["s", "y"]);
        let output = map.top("output").unwrap();
        assert_eq!(&text[output.value_span.clone()], "\"a.out\"");
        assert_eq!(text[..output.key_span.start].matches('\n').count() + 1, 6);
    }
}
