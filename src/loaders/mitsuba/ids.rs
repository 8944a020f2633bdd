//! Objects declared with an `id`. Mitsuba registers every id it reads, at top level or nested
//! inside another object (a BSDF inside a `twosided` or `bumpmap`, a texture given to a BSDF, a
//! medium given as a shape's interior), for every `<ref>` after it; an id declared twice is an
//! error that names both places.

use std::cell::RefCell;
use std::collections::HashMap;

use super::*;

/// One object type's declared ids: each object and where it was declared.
pub(super) struct Ids<T> {
    declared: RefCell<HashMap<String, (T, Location)>>,
}

impl<T: Clone> Ids<T> {
    pub(super) fn new() -> Self {
        Self {
            declared: RefCell::new(HashMap::new()),
        }
    }

    pub(super) fn get(&self, id: &str) -> Option<T> {
        self.declared
            .borrow()
            .get(id)
            .map(|(value, _)| value.clone())
    }

    pub(super) fn contains(&self, id: &str) -> bool {
        self.declared.borrow().contains_key(id)
    }

    /// Where `id` was declared.
    fn place(&self, id: &str) -> Option<Location> {
        self.declared.borrow().get(id).map(|(_, at)| at.clone())
    }

    pub(super) fn insert(&self, id: String, value: T, at: Location) {
        self.declared.borrow_mut().insert(id, (value, at));
    }
}

impl<'a, 'input> Reader<'a, 'input> {
    /// Reads the `<tag>` at `node` with `read` and, where it has an `id`, declares it among
    /// `ids`: refused before reading if the id is taken, remembered as failed (for the message
    /// of a later `<ref>`) if it cannot be read.
    pub(super) fn read_declared<T: Clone>(
        &self,
        ids: &Ids<T>,
        node: Node<'a, 'input>,
        tag: &str,
        read: impl FnOnce() -> Result<T, SceneError>,
    ) -> Result<T, SceneError> {
        let id = self.attr(node, "id")?;
        if let Some(id) = &id {
            self.refuse_taken(ids, node, tag, id)?;
        }
        match read() {
            Ok(value) => {
                if let Some(id) = id {
                    ids.insert(id, value.clone(), self.location(node));
                }
                Ok(value)
            }
            Err(e) => {
                if let Some(id) = id {
                    let line = self.location(node).line;
                    self.failed_ids.borrow_mut().insert(id, line);
                }
                Err(e)
            }
        }
    }

    /// An error at `node`'s `id` if `ids` holds `id` from another declaration, naming where.
    fn refuse_taken<T: Clone>(
        &self,
        ids: &Ids<T>,
        node: Node,
        tag: &str,
        id: &str,
    ) -> Result<(), SceneError> {
        match ids.place(id) {
            // A shapegroup's shapes are read again for each instance: the same declaration.
            Some(first) if first == self.location(node) => Ok(()),
            Some(first) => Err(self.attr_error(
                node,
                "id",
                format!(
                    "a second <{tag} id=\"{id}\"> (the first is at {first}): ids must be unique"
                ),
            )),
            None => Ok(()),
        }
    }
}
