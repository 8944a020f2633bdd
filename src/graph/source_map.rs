//! Where things are in a graph file. serde tells us what a RON file says but not where; this
//! small tokenizer and structural walk records the byte spans of each node, its fields and its
//! params keys, each edge and the output, so that every validation error can name a line.
//! It runs only on files serde already accepted, but never panics on any input.

use std::ops::Range;

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Str,
    Ident,
    Number,
    Open(u8),
    Close(u8),
    Punct(u8),
}

#[derive(Debug, Clone)]
struct Token {
    kind: Tok,
    span: Range<usize>,
}

fn tokenize(text: &str) -> Vec<Token> {
    let bytes = text.as_bytes();
    let mut tokens = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let c = bytes[i];
        let start = i;
        let kind = match c {
            b' ' | b'\t' | b'\r' | b'\n' => {
                i += 1;
                continue;
            }
            b'/' if bytes.get(i + 1) == Some(&b'/') => {
                while i < bytes.len() && bytes[i] != b'\n' {
                    i += 1;
                }
                continue;
            }
            b'/' if bytes.get(i + 1) == Some(&b'*') => {
                i += 2;
                while i < bytes.len() && !(bytes[i] == b'*' && bytes.get(i + 1) == Some(&b'/')) {
                    i += 1;
                }
                i = (i + 2).min(bytes.len());
                continue;
            }
            b'"' => {
                i += 1;
                while i < bytes.len() && bytes[i] != b'"' {
                    i += if bytes[i] == b'\\' { 2 } else { 1 };
                }
                i = (i + 1).min(bytes.len());
                Tok::Str
            }
            b'r' if matches!(bytes.get(i + 1), Some(b'"') | Some(b'#')) => {
                // Raw string r#"..."#: count the hashes, then find the matching close.
                let mut j = i + 1;
                while bytes.get(j) == Some(&b'#') {
                    j += 1;
                }
                let hashes = j - i - 1;
                if bytes.get(j) != Some(&b'"') {
                    i += 1;
                    tokens.push(Token {
                        kind: Tok::Ident,
                        span: start..i,
                    });
                    continue;
                }
                j += 1;
                loop {
                    if j >= bytes.len() {
                        break;
                    }
                    if bytes[j] == b'"'
                        && bytes[j + 1..]
                            .iter()
                            .take(hashes)
                            .filter(|&&b| b == b'#')
                            .count()
                            == hashes
                    {
                        j += 1 + hashes;
                        break;
                    }
                    j += 1;
                }
                i = j.min(bytes.len());
                Tok::Str
            }
            b'(' | b'[' | b'{' => {
                i += 1;
                Tok::Open(c)
            }
            b')' | b']' | b'}' => {
                i += 1;
                Tok::Close(c)
            }
            c if c.is_ascii_alphabetic() || c == b'_' => {
                while i < bytes.len() && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'_') {
                    i += 1;
                }
                Tok::Ident
            }
            c if c.is_ascii_digit() || c == b'-' || c == b'+' || c == b'.' => {
                i += 1;
                while i < bytes.len()
                    && (bytes[i].is_ascii_alphanumeric()
                        || matches!(bytes[i], b'.' | b'_' | b'+' | b'-'))
                {
                    i += 1;
                }
                Tok::Number
            }
            _ => {
                // Skip a whole UTF-8 character.
                i += text[i..].chars().next().map_or(1, char::len_utf8);
                Tok::Punct(c)
            }
        };
        tokens.push(Token {
            kind,
            span: start..i,
        });
    }
    tokens
}

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

struct Walker<'t> {
    text: &'t str,
    tokens: Vec<Token>,
}

impl Walker<'_> {
    fn slice(&self, i: usize) -> &str {
        self.tokens
            .get(i)
            .map_or("", |t| &self.text[t.span.clone()])
    }

    fn kind(&self, i: usize) -> Option<&Tok> {
        self.tokens.get(i).map(|t| &t.kind)
    }

    fn start(&self, i: usize) -> usize {
        self.tokens.get(i).map_or(self.text.len(), |t| t.span.start)
    }

    fn end(&self, i: usize) -> usize {
        self.tokens.get(i).map_or(self.text.len(), |t| t.span.end)
    }

    /// Index just past the group opened at `i` (which must be an Open token).
    fn skip_group(&self, i: usize) -> usize {
        let mut depth = 0usize;
        let mut j = i;
        while j < self.tokens.len() {
            match self.tokens[j].kind {
                Tok::Open(_) => depth += 1,
                Tok::Close(_) => {
                    depth = depth.saturating_sub(1);
                    if depth == 0 {
                        return j + 1;
                    }
                }
                _ => {}
            }
            j += 1;
        }
        j
    }

    /// Index just past the value starting at `i`: a group, or a token optionally followed by a
    /// group (`Some(..)`, `Name(..)`).
    fn skip_value(&self, i: usize) -> usize {
        match self.kind(i) {
            Some(Tok::Open(_)) => self.skip_group(i),
            Some(Tok::Ident) if matches!(self.kind(i + 1), Some(Tok::Open(b'('))) => {
                self.skip_group(i + 1)
            }
            Some(_) => i + 1,
            None => i,
        }
    }

    /// Fields of the struct whose `(` is at `open`. Returns them and the index past `)`.
    fn fields(&self, open: usize) -> (Vec<Field>, usize) {
        let end = self.skip_group(open);
        let mut fields = Vec::new();
        let mut i = open + 1;
        while i + 1 < end {
            let is_key = matches!(self.kind(i), Some(Tok::Ident))
                && matches!(self.kind(i + 1), Some(Tok::Punct(b':')));
            if !is_key {
                i = self.skip_value(i).max(i + 1);
                continue;
            }
            let value_start = i + 2;
            let value_end = self.skip_value(value_start).max(value_start);
            fields.push(Field {
                key: self.slice(i).to_string(),
                key_span: self.start(i)..self.end(i),
                value_span: self.start(value_start)
                    ..self
                        .end(value_end.saturating_sub(1))
                        .max(self.start(value_start)),
            });
            i = value_end;
        }
        (fields, end)
    }

    /// Index of the token starting at byte `offset`.
    fn token_at(&self, offset: usize) -> Option<usize> {
        self.tokens.iter().position(|t| t.span.start == offset)
    }

    /// Top-level-ish items of the list whose `[` starts at `offset`: spans of each element.
    fn list_items(&self, offset: usize) -> Vec<(usize, Range<usize>)> {
        let Some(open) = self.token_at(offset) else {
            return Vec::new();
        };
        if !matches!(self.kind(open), Some(Tok::Open(b'['))) {
            return Vec::new();
        }
        let end = self.skip_group(open);
        let mut items = Vec::new();
        let mut i = open + 1;
        while i + 1 < end {
            if matches!(self.kind(i), Some(Tok::Punct(b','))) {
                i += 1;
                continue;
            }
            let next = self.skip_value(i).max(i + 1);
            items.push((i, self.start(i)..self.end(next - 1)));
            i = next;
        }
        items
    }
}

/// Records where the parts of a graph file are.
pub fn map(text: &str) -> SourceMap {
    let walker = Walker {
        text,
        tokens: tokenize(text),
    };
    let Some(open) = walker.tokens.iter().position(|t| t.kind == Tok::Open(b'(')) else {
        return SourceMap::default();
    };
    let (top_fields, _) = walker.fields(open);
    let mut map = SourceMap {
        top_fields,
        ..Default::default()
    };
    if let Some(nodes) = map.top("nodes").cloned() {
        for (first, span) in walker.list_items(nodes.value_span.start) {
            // A node may be written `(..)` or `Node(..)`.
            let open = if matches!(walker.kind(first), Some(Tok::Ident)) {
                first + 1
            } else {
                first
            };
            let (fields, _) = if matches!(walker.kind(open), Some(Tok::Open(b'('))) {
                walker.fields(open)
            } else {
                (Vec::new(), open)
            };
            let params_fields = fields
                .iter()
                .find(|f| f.key == "params")
                .and_then(|f| walker.token_at(f.value_span.start))
                .filter(|&i| matches!(walker.kind(i), Some(Tok::Open(b'('))))
                .map(|i| walker.fields(i).0)
                .unwrap_or_default();
            map.nodes.push(NodeSpans {
                span,
                fields,
                params_fields,
            });
        }
    }
    if let Some(edges) = map.top("edges").cloned() {
        map.edges = walker
            .list_items(edges.value_span.start)
            .into_iter()
            .map(|(_, span)| span)
            .collect();
    }
    map
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
}
