//! Where things are in a RON file. serde says what a file means but not where, so graph and
//! scene errors found after parsing (an unknown pass kind, a negative radius in the third
//! shape) need their own map from the text to byte spans. This module is that map, shared by
//! both file kinds so they agree on what RON looks like: it knows line comments, nested block
//! comments, strings with escapes, raw strings (`r#"..."#`, any number of `#`), byte strings,
//! char literals, numbers and identifiers.
//!
//! It tolerates any input, never panics, and every span it reports lies on char boundaries of
//! the text: scene files are scanned before the RON parser has seen them (to refuse NaNs), and
//! a truncated or mangled file must still yield an error with a line, not a crash.

use std::ops::Range;

/// What a token is. Comments and white space are not tokens.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// A string, raw string or byte string, quotes and prefix included.
    Str,
    /// A char or byte literal, quotes included.
    Char,
    /// A name: a field, a variant, `Some`, `true`, `NaN`, `inf`, a raw identifier `r#name`.
    Ident,
    /// Anything starting with a digit, a sign or a point (`-1.5e3`, `0x1F`, `-inf`).
    Number,
    /// `(`, `[` or `{`.
    Open(u8),
    /// `)`, `]` or `}`.
    Close(u8),
    /// Any other single character (`,`, `:`, `#`, `!`, or something RON would refuse).
    Punct(char),
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Token {
    pub kind: Kind,
    pub span: Range<usize>,
}

/// Splits RON text into tokens, skipping white space and comments. Never fails: an
/// unterminated string or comment runs to the end of the text.
pub fn tokenize(text: &str) -> Vec<Token> {
    let bytes = text.as_bytes();
    let mut tokens = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let start = i;
        if let Some((kind, end)) = literal(text, i) {
            i = end.min(bytes.len());
            tokens.push(Token {
                kind,
                span: start..i,
            });
            continue;
        }
        let (kind, end) = match bytes[i] {
            b if b.is_ascii_whitespace() => {
                i += 1;
                continue;
            }
            b'/' if bytes.get(i + 1) == Some(&b'/') => {
                i = bytes[i..]
                    .iter()
                    .position(|&b| b == b'\n')
                    .map_or(bytes.len(), |p| i + p);
                continue;
            }
            b'/' if bytes.get(i + 1) == Some(&b'*') => {
                i = block_comment_end(bytes, i);
                continue;
            }
            b'r' if bytes.get(i + 1) == Some(&b'#') && text[i + 2..].starts_with(is_raw_char) => {
                (Kind::Ident, i + 2 + run_len(&text[i + 2..], is_raw_char))
            }
            b @ (b'(' | b'[' | b'{') => (Kind::Open(b), i + 1),
            b @ (b')' | b']' | b'}') => (Kind::Close(b), i + 1),
            b if b.is_ascii_digit() || matches!(b, b'-' | b'+' | b'.') => {
                let run = bytes[i + 1..]
                    .iter()
                    .take_while(|b| {
                        b.is_ascii_alphanumeric() || matches!(b, b'.' | b'_' | b'+' | b'-')
                    })
                    .count();
                (Kind::Number, i + 1 + run)
            }
            _ => {
                // `i` is always a char boundary: every step above ends on an ASCII byte or at
                // the end of the text, and this one steps over whole chars.
                let rest = &text[i..];
                let Some(c) = rest.chars().next() else {
                    break;
                };
                if is_ident_start(c) {
                    (Kind::Ident, i + run_len(rest, is_ident_char))
                } else {
                    (Kind::Punct(c), i + c.len_utf8())
                }
            }
        };
        i = end.min(bytes.len());
        tokens.push(Token {
            kind,
            span: start..i,
        });
    }
    tokens
}

/// The kind and end of the string or char literal (`"..."`, `r#"..."#`, `'c'`, each perhaps
/// with a `b` prefix) starting at `bytes[i]`, if one does. A `'` that starts no literal is left
/// to the caller, as RON has no other use for it.
fn literal(text: &str, i: usize) -> Option<(Kind, usize)> {
    let bytes = text.as_bytes();
    let quote = if bytes[i] == b'b' { i + 1 } else { i };
    match bytes.get(quote)? {
        b'"' => Some((Kind::Str, quoted_end(bytes, quote).1)),
        b'\'' => Some((Kind::Char, char_end(text, quote)?)),
        b'r' if raw_string_start(bytes, quote) => Some((Kind::Str, raw_end(bytes, quote).1)),
        _ => None,
    }
}

fn is_ident_start(c: char) -> bool {
    c == '_' || c.is_alphabetic()
}

fn is_ident_char(c: char) -> bool {
    c == '_' || c.is_alphanumeric()
}

/// Raw identifiers (`r#a.b-c`) may also hold `.`, `+` and `-`, as in RON.
fn is_raw_char(c: char) -> bool {
    is_ident_char(c) || matches!(c, '.' | '+' | '-')
}

/// Bytes taken by the leading chars of `s` that satisfy `keep`.
fn run_len(s: &str, keep: fn(char) -> bool) -> usize {
    s.find(|c: char| !keep(c)).unwrap_or(s.len())
}

/// Whether a raw string `r"`, `r#"`, `r##"`... starts at the `r` at `bytes[r]`.
fn raw_string_start(bytes: &[u8], r: usize) -> bool {
    let hashes = bytes[r + 1..].iter().take_while(|&&b| b == b'#').count();
    bytes.get(r + 1 + hashes) == Some(&b'"')
}

/// For the quoted string whose opening quote is `bytes[quote]`: the offset of its closing
/// quote and the offset just past it (both the end of the text if it is unterminated).
fn quoted_end(bytes: &[u8], quote: usize) -> (usize, usize) {
    let mut i = quote + 1;
    while i < bytes.len() {
        match bytes[i] {
            // The escaped byte may start a multi-byte char; its continuation bytes can never be
            // taken for a quote or a backslash, so stepping into them is harmless.
            b'\\' => i += 2,
            b'"' => return (i, i + 1),
            _ => i += 1,
        }
    }
    (bytes.len(), bytes.len())
}

/// For the raw string whose `r` is `bytes[r]` (see [`raw_string_start`]): the offset where its
/// contents end and the offset just past the closing `"#..#`.
fn raw_end(bytes: &[u8], r: usize) -> (usize, usize) {
    let hashes = bytes[r + 1..].iter().take_while(|&&b| b == b'#').count();
    let body = r + 2 + hashes;
    let mut i = body;
    while i < bytes.len() {
        let closes = bytes[i] == b'"'
            && bytes[i + 1..]
                .iter()
                .take(hashes)
                .filter(|&&b| b == b'#')
                .count()
                == hashes;
        if closes {
            return (i, i + 1 + hashes);
        }
        i += 1;
    }
    (bytes.len(), bytes.len())
}

/// The offset just past the char literal whose opening quote is at `quote`, or `None` when no
/// literal is written there (a stray `'`).
fn char_end(text: &str, quote: usize) -> Option<usize> {
    let rest = text.get(quote + 1..)?;
    let mut chars = rest.char_indices();
    let (_, first) = chars.next()?;
    let close = if first == '\\' {
        // An escape (`\n`, `\'`, `\x41`, `\u{1F600}`): the escaped char, then up to the quote.
        let (_, escaped) = chars.next()?;
        let after = 1 + escaped.len_utf8();
        after + rest[after..].find(['\'', '\n'])?
    } else {
        first.len_utf8()
    };
    (rest.as_bytes().get(close) == Some(&b'\'')).then_some(quote + 1 + close + 1)
}

/// The offset just past the block comment starting at `bytes[start]`. RON nests block comments,
/// so `/* a /* b */ c */` is one comment.
fn block_comment_end(bytes: &[u8], start: usize) -> usize {
    let mut depth = 1usize;
    let mut i = start + 2;
    while i + 1 < bytes.len() {
        match (bytes[i], bytes[i + 1]) {
            (b'/', b'*') => {
                depth += 1;
                i += 2;
            }
            (b'*', b'/') => {
                depth -= 1;
                i += 2;
                if depth == 0 {
                    return i;
                }
            }
            _ => i += 1,
        }
    }
    bytes.len()
}

/// The contents of a string token's text (between the quotes, escapes left as written), or
/// `None` if `token` is not a string. An unterminated string's contents run to its end.
pub fn string_contents(token: &str) -> Option<&str> {
    let unprefixed = token.strip_prefix('b').unwrap_or(token);
    let offset = token.len() - unprefixed.len();
    let bytes = token.as_bytes();
    let (start, end) = if unprefixed.starts_with('"') {
        (offset + 1, quoted_end(bytes, offset).0)
    } else if unprefixed.starts_with('r') && raw_string_start(bytes, offset) {
        let hashes = unprefixed[1..].len() - unprefixed[1..].trim_start_matches('#').len();
        (offset + 2 + hashes, raw_end(bytes, offset).0)
    } else {
        return None;
    };
    token.get(start..end.max(start))
}

/// The tokens of a text, with their bracket structure.
pub struct Outline<'t> {
    text: &'t str,
    tokens: Vec<Token>,
    /// For each opening bracket, the index of its closing one (`None` for other tokens and for
    /// brackets never closed). A closing bracket closes the innermost open group whatever its
    /// shape, as the RON parser would have refused a mismatch anyway.
    closes: Vec<Option<usize>>,
}

impl<'t> Outline<'t> {
    pub fn new(text: &'t str) -> Self {
        let tokens = tokenize(text);
        let mut closes = vec![None; tokens.len()];
        let mut open = Vec::new();
        for (i, token) in tokens.iter().enumerate() {
            match token.kind {
                Kind::Open(_) => open.push(i),
                Kind::Close(_) => {
                    if let Some(o) = open.pop() {
                        closes[o] = Some(i);
                    }
                }
                _ => {}
            }
        }
        Self {
            text,
            tokens,
            closes,
        }
    }

    pub fn tokens(&self) -> &[Token] {
        &self.tokens
    }

    /// The text of `token` (of this outline).
    pub fn text_of(&self, token: &Token) -> &'t str {
        self.text.get(token.span.clone()).unwrap_or("")
    }

    /// Index just past token `i`, or past its whole group if it opens one.
    fn skip(&self, i: usize) -> usize {
        match self.closes.get(i) {
            Some(Some(close)) => close + 1,
            Some(None) if matches!(self.tokens[i].kind, Kind::Open(_)) => self.tokens.len(),
            _ => i + 1,
        }
    }

    /// The bracket groups not inside any other, in file order.
    pub fn roots(&self) -> Vec<Group<'_>> {
        let mut roots = Vec::new();
        let mut i = 0;
        while i < self.tokens.len() {
            if matches!(self.tokens[i].kind, Kind::Open(_)) {
                roots.push(Group {
                    outline: self,
                    open: i,
                });
            }
            i = self.skip(i);
        }
        roots
    }

    /// The file's value: its last top-level group, so that `#![enable(...)]` before it is
    /// passed over.
    pub fn value(&self) -> Option<Group<'_>> {
        self.roots().pop()
    }
}

/// A bracket group `(...)`, `[...]` or `{...}` of an [`Outline`]. A group never closed runs to
/// the end of the text.
#[derive(Clone, Copy)]
pub struct Group<'a> {
    outline: &'a Outline<'a>,
    /// Index of the opening bracket.
    open: usize,
}

impl<'a> Group<'a> {
    /// The opening bracket: `b'('`, `b'['` or `b'{'`.
    pub fn bracket(&self) -> u8 {
        match self.outline.tokens[self.open].kind {
            Kind::Open(b) => b,
            _ => 0,
        }
    }

    pub fn is_closed(&self) -> bool {
        self.outline.closes[self.open].is_some()
    }

    /// From the opening bracket to the end of the closing one (or of the last token).
    pub fn span(&self) -> Range<usize> {
        span_of(&self.outline.tokens[self.open..self.outline.skip(self.open)])
    }

    /// The comma-separated items directly inside the group; empty ones (`[a,,b,]`) are left out.
    pub fn items(&self) -> Items<'a> {
        let outline = self.outline;
        Items {
            outline,
            next: self.open + 1,
            end: outline.closes[self.open].unwrap_or(outline.tokens.len()),
        }
    }

    /// The item `key: value` whose key is `key` (a name, or a string's contents for maps).
    pub fn field(&self, key: &str) -> Option<Item<'a>> {
        self.items()
            .find(|item| item.key().is_some_and(|k| k.name == key))
    }
}

/// The items of a [`Group`], in order.
pub struct Items<'a> {
    outline: &'a Outline<'a>,
    /// Token index where the next item starts.
    next: usize,
    /// Index of the closing bracket (or the token count).
    end: usize,
}

impl<'a> Iterator for Items<'a> {
    type Item = Item<'a>;

    fn next(&mut self) -> Option<Item<'a>> {
        let tokens = &self.outline.tokens;
        while self.next < self.end {
            let first = self.next;
            let mut i = first;
            while i < self.end && tokens[i].kind != Kind::Punct(',') {
                i = self.outline.skip(i);
            }
            let last = i.min(self.end);
            self.next = last + 1;
            if first < last {
                return Some(Item {
                    outline: self.outline,
                    first,
                    last,
                });
            }
        }
        None
    }
}

/// One entry of a group: `key: value` in structs and maps, a bare value in lists and tuples.
#[derive(Clone, Copy)]
pub struct Item<'a> {
    outline: &'a Outline<'a>,
    /// Token indices `first..last`, never empty.
    first: usize,
    last: usize,
}

/// The key of a `key: value` item.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Key<'a> {
    /// The name as written, or a string key's contents.
    pub name: &'a str,
    /// Whether it is a string (a map key) rather than a name (a struct field).
    pub quoted: bool,
    pub span: Range<usize>,
}

impl<'a> Item<'a> {
    /// From the first token of the item to the end of its last.
    pub fn span(&self) -> Range<usize> {
        span_of(self.tokens())
    }

    pub fn tokens(&self) -> &'a [Token] {
        &self.outline.tokens[self.first..self.last]
    }

    pub fn key(&self) -> Option<Key<'a>> {
        let [key, colon, ..] = self.tokens() else {
            return None;
        };
        if colon.kind != Kind::Punct(':') {
            return None;
        }
        let text = self.outline.text_of(key);
        let (name, quoted) = match key.kind {
            Kind::Ident => (text, false),
            Kind::Str => (string_contents(text)?, true),
            _ => return None,
        };
        Some(Key {
            name,
            quoted,
            span: key.span.clone(),
        })
    }

    /// Index of the value's first token.
    fn value_first(&self) -> usize {
        if self.key().is_some() {
            self.first + 2
        } else {
            self.first
        }
    }

    /// The value of a `key: value` item, or the whole item. Empty (just past the colon) when
    /// nothing follows the colon.
    pub fn value_span(&self) -> Range<usize> {
        let value = &self.outline.tokens[self.value_first()..self.last];
        if value.is_empty() {
            let end = self.span().end;
            end..end
        } else {
            span_of(value)
        }
    }

    /// The bracket group of the value: the value itself (`(..)`, `[..]`, `{..}`), or what follows
    /// a name (`Some(..)`, `Sphere(..)`).
    pub fn group(&self) -> Option<Group<'a>> {
        let first = self.value_first();
        let kinds = |i: usize| (i < self.last).then(|| self.outline.tokens[i].kind);
        let open = match (kinds(first)?, kinds(first + 1)) {
            (Kind::Open(_), _) => first,
            (Kind::Ident, Some(Kind::Open(b'('))) => first + 1,
            _ => return None,
        };
        Some(Group {
            outline: self.outline,
            open,
        })
    }
}

/// From the start of the first token to the end of the last (empty for no tokens).
fn span_of(tokens: &[Token]) -> Range<usize> {
    match (tokens.first(), tokens.last()) {
        (Some(first), Some(last)) => first.span.start..last.span.end,
        _ => 0..0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 1-based line of byte `offset`.
    fn line(text: &str, offset: usize) -> usize {
        text[..offset].matches('\n').count() + 1
    }

    fn keys<'a>(group: Group<'a>) -> Vec<&'a str> {
        group
            .items()
            .filter_map(|i| i.key())
            .map(|k| k.name)
            .collect()
    }

    fn kinds(text: &str) -> Vec<(Kind, &str)> {
        tokenize(text)
            .into_iter()
            .map(|t| (t.kind, &text[t.span]))
            .collect()
    }

    const GRAPH: &str = r##"// comment (with parens
(
    version: 1,
    nodes: [
        (name: "a", pass: "k", params: (label: r#"say "hi" // not a comment )"#, n: 2)),
        Node(name: "b", pass: "k", params: (x: Some((1, 2)), y: "s)")),
    ],
    edges: ["a.out -> b.in", /* c */ "b.out -> a.in"],
    output: "b.out",
)"##;

    const SCENE: &str = r##"#![enable(implicit_some)]
(
    camera: (origin: (0, 0, 5), target: (0, 0, 0), fov_x: 40, width: 8, height: 8),
    materials: {
        r#"a" // )"#: Mirror,
        "m": Diffuse(reflectance: (0.5, 0.5, 0.5)),
    },
    shapes: [
        (shape: Obj(path: r#"mesh" // (1).obj"#), material: "m"),
        (shape: Cube, material: r#"a" // )"#, emission: (1, 1, 1)),
    ],
)"##;

    #[test]
    fn tokens_of_every_kind() {
        assert_eq!(
            kinds(r##"a_1 r#x.y -1.5e3 +inf .5 "s\"" r#"r"# br"b" b"c" 'x' '\'' b'y' (]{ , : #"##),
            [
                (Kind::Ident, "a_1"),
                (Kind::Ident, "r#x.y"),
                (Kind::Number, "-1.5e3"),
                (Kind::Number, "+inf"),
                (Kind::Number, ".5"),
                (Kind::Str, r#""s\"""#),
                (Kind::Str, r##"r#"r"#"##),
                (Kind::Str, r#"br"b""#),
                (Kind::Str, r#"b"c""#),
                (Kind::Char, "'x'"),
                (Kind::Char, r"'\''"),
                (Kind::Char, "b'y'"),
                (Kind::Open(b'('), "("),
                (Kind::Close(b']'), "]"),
                (Kind::Open(b'{'), "{"),
                (Kind::Punct(','), ","),
                (Kind::Punct(':'), ":"),
                (Kind::Punct('#'), "#"),
            ]
        );
        assert_eq!(
            kinds("a /* x /* y */ \" */ b // c )\n/*/ */ d /* unterminated /* */"),
            [(Kind::Ident, "a"), (Kind::Ident, "b"), (Kind::Ident, "d")]
        );
        // Names that merely start like a raw string or a byte string are names.
        assert_eq!(
            kinds("radius b r"),
            [
                (Kind::Ident, "radius"),
                (Kind::Ident, "b"),
                (Kind::Ident, "r")
            ]
        );
    }

    #[test]
    fn string_contents_strip_quotes_and_prefixes() {
        assert_eq!(string_contents(r#""a\"b""#), Some(r#"a\"b"#));
        assert_eq!(string_contents(r###"r##"a"#b"##"###), Some(r##"a"#b"##));
        assert_eq!(string_contents(r#"br"x""#), Some("x"));
        assert_eq!(string_contents(r#"b"x""#), Some("x"));
        assert_eq!(string_contents("\"unterminated"), Some("unterminated"));
        assert_eq!(
            string_contents("r#\"unterminated\""),
            Some("unterminated\"")
        );
        assert_eq!(string_contents("\""), Some(""));
        assert_eq!(string_contents("name"), None);
    }

    #[test]
    fn chars_that_look_like_brackets_or_quotes_stay_inside_their_literal() {
        let text = r#"(c: ')', d: '"', e: '\u{1F600}', f: 1)"#;
        let outline = Outline::new(text);
        let top = outline.value().unwrap();
        assert_eq!(keys(top), ["c", "d", "e", "f"]);
        assert!(top.is_closed());
        // A lone quote is no literal: it must not swallow the rest of the text.
        assert_eq!(
            keys(Outline::new("(a: ', b: 2)").value().unwrap()),
            ["a", "b"]
        );
    }

    /// The old graph tokenizer's own test, on the shared outline.
    #[test]
    fn finds_nodes_params_and_edges_of_a_graph() {
        let outline = Outline::new(GRAPH);
        let top = outline.value().unwrap();
        assert_eq!(keys(top), ["version", "nodes", "edges", "output"]);
        let nodes: Vec<_> = top
            .field("nodes")
            .unwrap()
            .group()
            .unwrap()
            .items()
            .collect();
        assert_eq!(nodes.len(), 2);
        let b = nodes[1].group().unwrap();
        assert_eq!(&GRAPH[b.field("pass").unwrap().value_span()], "\"k\"");
        let params = b.field("params").unwrap();
        assert_eq!(&GRAPH[params.value_span()], "(x: Some((1, 2)), y: \"s)\")");
        assert_eq!(keys(params.group().unwrap()), ["x", "y"]);
        let edges: Vec<_> = top
            .field("edges")
            .unwrap()
            .group()
            .unwrap()
            .items()
            .map(|e| &GRAPH[e.span()])
            .collect();
        assert_eq!(edges, ["\"a.out -> b.in\"", "\"b.out -> a.in\""]);
        assert_eq!(
            &GRAPH[top.field("output").unwrap().value_span()],
            "\"b.out\""
        );
    }

    /// A raw string holding `"`, `//` and `)` must stay one token, or the `)` would end the
    /// params group and `n` would be lost. (The graph tokenizer knew raw strings; the scene
    /// one did not, see the next test.)
    #[test]
    fn a_raw_string_in_a_graph_hides_quotes_comments_and_brackets() {
        let outline = Outline::new(GRAPH);
        let top = outline.value().unwrap();
        let nodes: Vec<_> = top
            .field("nodes")
            .unwrap()
            .group()
            .unwrap()
            .items()
            .collect();
        let a = nodes[0].group().unwrap();
        let params = a.field("params").unwrap();
        assert_eq!(
            &GRAPH[params.value_span()],
            r##"(label: r#"say "hi" // not a comment )"#, n: 2)"##
        );
        let params = params.group().unwrap();
        assert_eq!(keys(params), ["label", "n"]);
        let label = params.field("label").unwrap();
        assert_eq!(
            &GRAPH[label.value_span()],
            r##"r#"say "hi" // not a comment )"#"##
        );
        let n = params.field("n").unwrap().key().unwrap();
        assert_eq!(line(GRAPH, n.span.start), 5);
        assert_eq!(line(GRAPH, nodes[1].span().start), 6);
        assert_eq!(line(GRAPH, top.field("output").unwrap().span().start), 9);
    }

    /// The same in a scene: the scene tokenizer took `r#` for a word and `"a"` for a whole
    /// string, so `// )"#: Mirror,` became a comment and the material keys were lost.
    #[test]
    fn a_raw_string_in_a_scene_hides_quotes_comments_and_brackets() {
        let outline = Outline::new(SCENE);
        let top = outline.value().unwrap();
        assert_eq!(keys(top), ["camera", "materials", "shapes"]);
        let materials = top.field("materials").unwrap().group().unwrap();
        let keys: Vec<_> = materials.items().filter_map(|i| i.key()).collect();
        assert_eq!(
            keys.iter().map(|k| (k.name, k.quoted)).collect::<Vec<_>>(),
            [(r#"a" // )"#, true), ("m", true)]
        );
        assert_eq!(line(SCENE, keys[0].span.start), 5);
        assert_eq!(line(SCENE, keys[1].span.start), 6);
        let shapes: Vec<_> = top
            .field("shapes")
            .unwrap()
            .group()
            .unwrap()
            .items()
            .collect();
        assert_eq!(shapes.len(), 2);
        let obj = shapes[0].group().unwrap();
        let path = obj
            .field("shape")
            .unwrap()
            .group()
            .unwrap()
            .field("path")
            .unwrap();
        assert_eq!(&SCENE[path.value_span()], r##"r#"mesh" // (1).obj"#"##);
        assert_eq!(line(SCENE, shapes[1].span().start), 10);
        let emission = shapes[1]
            .tokens()
            .iter()
            .find(|t| outline.text_of(t) == "emission")
            .unwrap();
        assert_eq!(line(SCENE, emission.span.start), 10);
    }

    /// RON nests block comments; the graph tokenizer ended one at its first `*/`, leaving
    /// `c */` as tokens that became stray list elements before the node.
    #[test]
    fn a_nested_block_comment_before_a_graph_field() {
        let text = "(\n    version: 1,\n    /* a /* b */ c */ nodes: [\n        /* a /* b */ c */ (name: \"a\", pass: \"k\"),\n    ],\n    output: \"a.out\",\n)";
        let outline = Outline::new(text);
        let top = outline.value().unwrap();
        assert_eq!(keys(top), ["version", "nodes", "output"]);
        let nodes = top.field("nodes").unwrap();
        assert_eq!(line(text, nodes.key().unwrap().span.start), 3);
        let nodes: Vec<_> = nodes.group().unwrap().items().collect();
        assert_eq!(nodes.len(), 1);
        assert_eq!(&text[nodes[0].span()], "(name: \"a\", pass: \"k\")");
        assert_eq!(line(text, nodes[0].span().start), 4);
        assert_eq!(line(text, top.field("output").unwrap().span().start), 6);
    }

    /// The scene tokenizer already nested them; this keeps it so.
    #[test]
    fn a_nested_block_comment_before_a_scene_field() {
        let text = "(\n /* a /* b */ c */ camera: (fov_x: 40),\n materials: { /* a /* b */ c */ \"m\": Mirror },\n shapes: [\n  (shape: Cube),\n  /* a /* b */ c */ (shape: Cube, material: \"m\"),\n ],\n)";
        let outline = Outline::new(text);
        let top = outline.value().unwrap();
        assert_eq!(keys(top), ["camera", "materials", "shapes"]);
        assert_eq!(line(text, top.field("camera").unwrap().span().start), 2);
        let m = top
            .field("materials")
            .unwrap()
            .group()
            .unwrap()
            .field("m")
            .unwrap();
        assert_eq!(&text[m.span()], "\"m\": Mirror");
        let shapes: Vec<_> = top
            .field("shapes")
            .unwrap()
            .group()
            .unwrap()
            .items()
            .collect();
        assert_eq!(shapes.len(), 2);
        assert_eq!(&text[shapes[1].span()], "(shape: Cube, material: \"m\")");
        assert_eq!(line(text, shapes[1].span().start), 6);
    }

    /// A file cut short: groups and strings left open run to the end, and what came before
    /// is still found where it is.
    #[test]
    fn a_truncated_file_keeps_what_it_has() {
        let cut = GRAPH.find("// not a comment").unwrap();
        let text = &GRAPH[..cut];
        let outline = Outline::new(text);
        let top = outline.value().unwrap();
        assert!(!top.is_closed());
        assert_eq!(keys(top), ["version", "nodes"]);
        let a = top
            .field("nodes")
            .unwrap()
            .group()
            .unwrap()
            .items()
            .next()
            .unwrap();
        let params = a.group().unwrap().field("params").unwrap().group().unwrap();
        assert_eq!(keys(params), ["label"]);
        let label = params.field("label").unwrap();
        assert_eq!(&text[label.value_span()], r##"r#"say "hi" "##);
        assert_eq!(line(text, label.span().start), 5);
        assert_eq!(top.span().end, text.len());
    }

    /// Cuts at every char and stray brackets, quotes and comment openers: no panic, and every
    /// reported span can slice the text.
    #[test]
    fn never_panics_and_spans_are_char_boundaries() {
        let texts = [GRAPH, SCENE, "(a: \"é☃\", b: ☃, ü: 'ß', c: r#\"→\"#)"];
        let check = |text: &str| {
            let outline = Outline::new(text);
            for t in outline.tokens() {
                assert!(text.get(t.span.clone()).is_some(), "{text:?} {t:?}");
            }
            let mut stack: Vec<_> = outline.roots();
            while let Some(group) = stack.pop() {
                assert!(text.get(group.span()).is_some());
                for item in group.items() {
                    assert!(text.get(item.span()).is_some());
                    assert!(text.get(item.value_span()).is_some());
                    if let Some(key) = item.key() {
                        assert!(text.get(key.span).is_some());
                    }
                    stack.extend(item.group());
                }
            }
        };
        for text in texts {
            for (end, _) in text.char_indices() {
                check(&text[..end]);
                check(&text[end..]);
            }
        }
        for text in [
            "", "(", ")", "]]((", "r", "r#", "r#\"", "b'", "'", "'\\", "'\\u{", "/*", "/* /*",
            "/*/", "\"\\", "\"\\é", "(a:", "(a: ,", ",,,", "(::)",
        ] {
            check(text);
        }
    }

    #[test]
    fn non_ascii_strings_and_names_keep_their_spans() {
        let text = "(\n    name: \"grüße → ☃\",\n    ☃: 1,\n    größe: 'ß',\n    pass: \"k\",\n)";
        let outline = Outline::new(text);
        let top = outline.value().unwrap();
        assert_eq!(keys(top), ["name", "größe", "pass"]);
        let name = top.field("name").unwrap();
        assert_eq!(&text[name.value_span()], "\"grüße → ☃\"");
        assert_eq!(&text[top.field("größe").unwrap().value_span()], "'ß'");
        let pass = top.field("pass").unwrap();
        assert_eq!(line(text, pass.span().start), 5);
        assert_eq!(&text[pass.value_span()], "\"k\"");
        // The `☃` is no name, so it is a lone token and `☃: 1` has no key; it is still an item.
        assert_eq!(top.items().count(), 4);
    }

    #[test]
    fn the_value_is_the_last_top_level_group() {
        let outline = Outline::new(SCENE);
        assert_eq!(outline.roots().len(), 2);
        let value = outline.value().unwrap();
        assert_eq!(value.bracket(), b'(');
        assert_eq!(line(SCENE, value.span().start), 2);
        assert!(Outline::new("// nothing").value().is_none());
    }
}
