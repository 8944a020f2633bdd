//! The graphs shipped in hppm's `graphs/` folder, compiled into the library by name, and how a
//! graph file's text is found: a file, or where none is there, the bundled graph it names.

use std::path::{Path, PathBuf};

/// `bundled!("pt")`: the entry of graphs/pt.ron in [`BUNDLED_GRAPHS`].
macro_rules! bundled {
    ($name:literal) => {
        (
            $name,
            concat!("graphs/", $name, ".ron"),
            include_str!(concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/graphs/",
                $name,
                ".ron"
            )),
        )
    };
}

/// The graphs shipped in `graphs/`, by name (the file name without `.ron`), with the path
/// errors name them by and their text, compiled into the library.
pub const BUNDLED_GRAPHS: &[(&str, &str, &str)] = &[
    bundled!("hybrid"),
    bundled!("pt"),
    bundled!("hybrid_ppm"),
    bundled!("hybrid_pppm"),
    bundled!("hybrid_lbvh"),
    bundled!("hybrid_grid"),
    bundled!("hybrid_all_depths"),
    bundled!("hybrid_first_vertex"),
    bundled!("hybrid_glossy"),
    bundled!("ppm_only"),
];

/// A bundled graph's path (for messages) and text.
pub fn bundled_graph(name: &str) -> Result<(&'static str, &'static str), crate::Error> {
    BUNDLED_GRAPHS
        .iter()
        .find(|(n, _, _)| *n == name)
        .map(|(_, file, text)| (*file, *text))
        .ok_or_else(|| {
            let names: Vec<&str> = BUNDLED_GRAPHS.iter().map(|g| g.0).collect();
            crate::Error::Other(format!(
                "no bundled graph \"{name}\"; the bundled graphs: {}",
                names.join(", ")
            ))
        })
}

/// The text of the graph file at `name_or_path`, or, where there is no such file, of the
/// bundled graph it names: by name (`hybrid`) or by its path in hppm's repository
/// (`graphs/hybrid.ron`, which a program run away from the repository is still given). Returns
/// the path errors name with the text.
pub fn read_graph(name_or_path: &Path) -> Result<(PathBuf, String), crate::Error> {
    let missing = match std::fs::read_to_string(name_or_path) {
        Ok(text) => return Ok((name_or_path.to_path_buf(), text)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => e,
        Err(e) => {
            return Err(crate::Error::Other(format!(
                "{}: {e}",
                name_or_path.display()
            )));
        }
    };
    let bundled = BUNDLED_GRAPHS
        .iter()
        .find(|(name, file, _)| name_or_path == Path::new(name) || name_or_path.ends_with(file));
    match bundled {
        Some((_, file, text)) => Ok((PathBuf::from(file), text.to_string())),
        None => {
            let names: Vec<&str> = BUNDLED_GRAPHS.iter().map(|g| g.0).collect();
            Err(crate::Error::Other(format!(
                "{}: {missing} (nor is it a bundled graph: {})",
                name_or_path.display(),
                names.join(", ")
            )))
        }
    }
}
