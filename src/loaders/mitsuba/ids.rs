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

/// The tags whose ids [`Ids`] checks as they are read.
const READ_WITH_IDS: &[&str] = &["bsdf", "texture", "medium"];

impl Reader<'_, '_> {
    /// Mitsuba keeps one table of ids for every object (0.6's scene handler and Mitsuba 3's
    /// parser both refuse a second declaration): an id given twice where [`Ids`] does not see
    /// it (a shape, an emitter, a sensor, or two objects of different types) is an error at the
    /// second, naming the first.
    pub(super) fn check_unique_ids(&self) {
        let mut seen: HashMap<&str, Node> = HashMap::new();
        let declarations = self
            .files
            .iter()
            .flat_map(|f| f.doc.descendants())
            .filter(|n| n.is_element() && !matches!(n.tag_name().name(), "ref" | "alias"));
        for node in declarations {
            let Some(id) = node.attribute("id") else {
                continue;
            };
            let Some(first) = seen.get(id) else {
                seen.insert(id, node);
                continue;
            };
            let (tag, first_tag) = (node.tag_name().name(), first.tag_name().name());
            if tag == first_tag && READ_WITH_IDS.contains(&tag) {
                continue;
            }
            let at = self.location(*first);
            self.report(self.attr_error(
                node,
                "id",
                format!(
                    "{}: id \"{id}\" is declared already, by the {} at {}:{} (Mitsuba refuses \
                     an id given twice)",
                    describe_object(node),
                    describe_object(*first),
                    at.file.display(),
                    at.line
                ),
            ));
        }
    }
}
