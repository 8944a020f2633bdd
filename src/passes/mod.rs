//! The registry of pass kinds: every kind a graph file may name.

pub mod path_trace;

use crate::graph::pass::PassKind;

/// All pass kinds, in the order `hppm info` lists them.
pub fn registry() -> &'static [PassKind] {
    static KINDS: &[PassKind] = &[path_trace::KIND];
    KINDS
}
