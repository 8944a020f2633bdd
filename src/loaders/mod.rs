//! The scene loaders: Mitsuba 3 XML (`mitsuba/`, with its spectra and the table of the plugins
//! it reads), our RON format, OBJ, PLY and Mitsuba's serialized meshes. Each produces a
//! [`Scene`]; [`load`] picks one by the file's extension.

pub mod mitsuba;
pub mod obj;
pub mod plugins;
pub mod ply;
pub mod ron_format;
pub mod serialized;
pub mod spectrum;
pub mod vol;

use std::path::Path;

use crate::bsdfs::BsdfRegistry;
use crate::scene::{Scene, SceneError};
pub use mitsuba::RuleSet;

pub(crate) fn read_text(path: &Path) -> Result<String, SceneError> {
    std::fs::read_to_string(path).map_err(|source| SceneError::Io {
        file: path.to_path_buf(),
        source,
    })
}

/// Everything a scene file's check finds: the problems that keep it from rendering (`errors`),
/// those it renders without (`warnings`: an integrator whose algorithm the graph replaces, a
/// property only old Mitsuba versions read), and the scene when there are no errors. Each
/// problem names its file, line and column.
#[derive(Debug)]
pub struct Report {
    pub scene: Option<Scene>,
    pub errors: Vec<SceneError>,
    pub warnings: Vec<SceneError>,
    /// The rules each file was read with: Mitsuba 3's, or 0.6's for a file older than 2.0.
    pub rule_sets: Vec<RuleSet>,
    /// What reading a Mitsuba 0.5/0.6 file changed to read it with Mitsuba 3's plugins (a
    /// property renamed, a preset expanded, 0.6's default applied), at its place; `hppm check
    /// --verbose` lists them.
    pub upgrades: Vec<SceneError>,
    /// Each plugin met (`"bsdf diffuse"`) and every property name its reader looked for,
    /// given or not: what the loader reads, to hold the plugin table to it.
    pub properties_read: std::collections::BTreeMap<String, std::collections::BTreeSet<String>>,
}

impl Report {
    /// The scene, or every error as one.
    pub fn into_result(self) -> Result<Scene, SceneError> {
        match self.scene {
            Some(scene) if self.errors.is_empty() => Ok(scene),
            _ => Err(SceneError::from_problems(self.errors)),
        }
    }

    pub(crate) fn failed(error: SceneError) -> Self {
        Report {
            scene: None,
            errors: vec![error],
            warnings: Vec::new(),
            rule_sets: Vec::new(),
            upgrades: Vec::new(),
            properties_read: Default::default(),
        }
    }
}

/// Checks a scene file: every problem a Mitsuba XML file has, at once (see
/// [`mitsuba::check_with`]); other formats stop at their first.
pub fn check_with(path: &Path, defines: &[(String, String)]) -> Report {
    check_in(path, defines, BsdfRegistry::builtin_ref())
}

/// [`check_with`], reading Mitsuba BSDFs with the units of `bsdfs` (a program's own among them).
pub fn check_in(path: &Path, defines: &[(String, String)], bsdfs: &BsdfRegistry) -> Report {
    if is_mitsuba(path) {
        return mitsuba::check_file_with(path, defines, bsdfs);
    }
    match load_with(path, defines) {
        Ok(scene) => Report {
            scene: Some(scene),
            errors: Vec::new(),
            warnings: Vec::new(),
            rule_sets: Vec::new(),
            upgrades: Vec::new(),
            properties_read: Default::default(),
        },
        Err(e) => Report::failed(e),
    }
}

/// [`load_with`] with the BSDF units of `bsdfs`, handing each warning (what the scene renders
/// without) to `warn`.
pub fn load_reporting(
    path: &Path,
    defines: &[(String, String)],
    bsdfs: &BsdfRegistry,
    mut warn: impl FnMut(&SceneError),
) -> Result<Scene, SceneError> {
    let report = check_in(path, defines, bsdfs);
    report.warnings.iter().for_each(&mut warn);
    report.into_result()
}

fn is_mitsuba(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("xml"))
}

/// Loads a scene by extension: `.xml` (Mitsuba 3), `.ron` (ours) or `.obj` / `.ply` (a bare mesh,
/// given a default camera and light so it can be looked at).
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    load_with(path, &[])
}

/// [`load`] with Mitsuba `-D name=value` parameters (see [`mitsuba::load_with`]); only Mitsuba
/// XML scenes take them.
pub fn load_with(path: &Path, defines: &[(String, String)]) -> Result<Scene, SceneError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    match ext.as_str() {
        "xml" => mitsuba::load_with(path, defines),
        _ if !defines.is_empty() => Err(SceneError::File {
            file: path.to_path_buf(),
            message: "-D parameters apply to Mitsuba XML scenes only (their <default>s)".into(),
        }),
        "ron" => ron_format::load(path),
        "obj" => obj::load_scene(path),
        "ply" => obj::framed_scene(path, ply::load(path)?.triangles),
        _ => Err(SceneError::File {
            file: path.to_path_buf(),
            message: "unknown scene format (expected .xml, .ron, .obj or .ply)".into(),
        }),
    }
}
