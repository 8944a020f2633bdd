//! The registry a render is built from: the pass kinds a graph file may name, the WGSL modules
//! their shaders may import, and how each scene need a pass declares is answered. The built-in
//! passes are one registry ([`Registry::builtin`]); a program adds its own kinds, modules and
//! needs to it as values, without changing hppm:
//!
//! ```no_run
//! # use hppm::passes::Registry;
//! # static MY_KIND: hppm::graph::pass::PassKind = hppm::passes::resolve::KIND;
//! let registry = Registry::builtin().with(&MY_KIND);
//! let graph = registry.load_graph(std::path::Path::new("graphs/mine.ron"))?;
//! # Ok::<(), hppm::Error>(())
//! ```

use std::path::Path;

use crate::bsdfs::{BsdfPlugin, BsdfRegistry};
use crate::gpu::shaders::{ShaderFile, ShaderLibrary, WgslModule, defs_of};
use crate::gpu_scene::TablePlacement;
use crate::graph::pass::{PassKind, SceneNeed};
use crate::graph::{GraphErrors, ValidGraph};
use crate::scene::{Scene, SceneFeatures};

/// Whether a scene meets a need: the scene, its features (computed once per render) and the
/// need as the pass declared it.
pub type NeedTest = fn(&Scene, &SceneFeatures, &SceneNeed) -> bool;

/// Pass kinds, importable WGSL modules, scene-need tests and the BSDF units, by value.
#[derive(Clone)]
pub struct Registry {
    kinds: Vec<&'static PassKind>,
    /// Modules a program added, composed after hppm's own.
    modules: Vec<ShaderFile>,
    needs: Vec<(&'static str, NeedTest)>,
    bsdfs: BsdfRegistry,
}

impl std::fmt::Debug for Registry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let kinds: Vec<&str> = self.kinds.iter().map(|k| k.name).collect();
        let modules: Vec<&str> = self.modules.iter().map(|m| m.path).collect();
        let bsdfs: Vec<&str> = self.bsdfs.units().iter().map(|u| u.name).collect();
        let needs: Vec<&str> = self.needs.iter().map(|n| n.0).collect();
        f.debug_struct("Registry")
            .field("kinds", &kinds)
            .field("modules", &modules)
            .field("needs", &needs)
            .field("bsdfs", &bsdfs)
            .finish()
    }
}

impl Default for Registry {
    fn default() -> Self {
        Self::builtin()
    }
}

impl Registry {
    /// hppm's own passes, shared WGSL modules (`shaders/common/`) and scene needs.
    pub fn builtin() -> Self {
        Self {
            kinds: super::builtin_kinds().to_vec(),
            modules: Vec::new(),
            needs: vec![
                (super::SPECULAR_SURFACE.name, |_, features, _| {
                    features.has_specular_surface()
                }),
                (
                    super::SPECULAR_OR_GLOSSY_SURFACE.name,
                    |_, features, need| features.has_specular_or_glossy_surface(need.glossy_below),
                ),
            ],
            bsdfs: BsdfRegistry::builtin(),
        }
    }

    /// Adds a pass kind; one of the same name replaces the kind registered before (a program
    /// may swap a built-in's implementation).
    pub fn with(mut self, kind: &'static PassKind) -> Self {
        match self.kinds.iter_mut().find(|k| k.name == kind.name) {
            Some(old) => *old = kind,
            None => self.kinds.push(kind),
        }
        self
    }

    /// Adds an importable WGSL module (its file's `#define_import_path` names it), after the
    /// ones already registered: it may import those, and later ones may import it.
    pub fn with_module(mut self, module: ShaderFile) -> Self {
        self.modules.push(module);
        self
    }

    /// Adds a BSDF unit (its Mitsuba types, kinds and WGSL; see [`BsdfRegistry::with`]): scenes
    /// loaded with [`Self::bsdfs`] may use it, and every library this registry builds composes
    /// its WGSL and dispatches to it.
    pub fn with_bsdf(mut self, unit: &'static BsdfPlugin) -> Self {
        self.bsdfs = self.bsdfs.with(unit);
        self
    }

    /// The BSDF units scenes are loaded with and kernels dispatch to.
    pub fn bsdfs(&self) -> &BsdfRegistry {
        &self.bsdfs
    }

    /// Adds (or replaces) the test that answers the scene need `name` (a [`SceneNeed`] a pass
    /// declares in [`crate::graph::pass::Pass::needs`]). A need no test answers is never met,
    /// so its node is pruned.
    pub fn with_need(mut self, name: &'static str, test: NeedTest) -> Self {
        self.needs.retain(|(n, _)| *n != name);
        self.needs.push((name, test));
        self
    }

    /// The kinds, built-in first, in the order `hppm info` lists them.
    pub fn kinds(&self) -> &[&'static PassKind] {
        &self.kinds
    }

    pub fn kind(&self, name: &str) -> Option<&'static PassKind> {
        self.kinds.iter().find(|k| k.name == name).copied()
    }

    /// The importable modules, in dependency order: hppm's own with the BSDFs' generated from
    /// [`Self::bsdfs`], then the program's.
    pub fn modules(&self) -> Vec<WgslModule> {
        let own = super::common_modules(&self.bsdfs);
        own.into_iter()
            .chain(self.modules.iter().map(|&file| WgslModule::File(file)))
            .collect()
    }

    /// Whether `scene` (with `features`) meets `need`, as the need's registered test says.
    pub fn scene_meets(&self, scene: &Scene, features: &SceneFeatures, need: &SceneNeed) -> bool {
        self.needs
            .iter()
            .find(|(name, _)| *name == need.name)
            .is_some_and(|(_, test)| test(scene, features, need))
    }

    /// Reads and validates a graph file against these kinds; a bundled graph's name, or its
    /// repository path where no file is there, stands for its compiled-in text
    /// ([`crate::graph::bundled::read_graph`]).
    pub fn load_graph(&self, path: &Path) -> Result<ValidGraph, crate::Error> {
        let (file, text) = crate::graph::bundled::read_graph(path)?;
        Ok(self.parse_graph(&file, &text)?)
    }

    /// Validates graph `text` (read from `path`, which errors name) against these kinds.
    pub fn parse_graph(&self, path: &Path, text: &str) -> Result<ValidGraph, GraphErrors> {
        crate::graph::parse_graph(path, text, &self.kinds)
    }

    /// One of the graphs shipped in hppm's `graphs/` folder, by name (`"hybrid"`, `"pt"`, ...;
    /// see [`crate::graph::bundled::BUNDLED_GRAPHS`]), validated against these kinds.
    pub fn bundled_graph(&self, name: &str) -> Result<ValidGraph, crate::Error> {
        let (file, text) = crate::graph::bundled::bundled_graph(name)?;
        Ok(self.parse_graph(Path::new(file), text)?)
    }

    /// The shader library these passes compose against for `scene` on a device with or without
    /// float atomics, with its tables bound as `placement` says.
    pub fn shader_library(
        &self,
        float_atomics: bool,
        scene: &Scene,
        placement: &TablePlacement,
    ) -> Result<ShaderLibrary, crate::Error> {
        let mut defs = super::scene_defs(&scene.features(), &self.bsdfs);
        if crate::scene::texture::has_float_bitmaps(&scene.textures) {
            defs.extend(defs_of(["FLOAT_TEXELS"]));
        }
        defs.extend(placement.defs());
        Ok(ShaderLibrary::new(float_atomics, defs, &self.modules())?)
    }

    /// Every kind's reference (`hppm info --markdown`, docs/pass-kinds.md).
    pub fn markdown(&self) -> String {
        let mut out = String::from(
            "<!-- Generated by `hppm info --markdown` from the pass kinds' declarations. -->\n\n\
             # Pass kinds\n\n\
             Each kind's slots as its `PassKind` declares them and the params its params struct \
             accepts (what each means is documented on that struct, in the kind's file under \
             `src/passes/`). Flags: *persistent* outputs keep their contents across iterations; \
             *optional* inputs may stay unconnected; a *previous iteration* input reads what its \
             producer held at the end of the last iteration; *kept* inputs need the resource \
             written once; *observe only* inputs do not count as consumers; at most one consumer \
             reads an output through an *exclusive* input; a *required* output must feed a \
             node.\n",
        );
        for kind in &self.kinds {
            out.push('\n');
            out.push_str(&kind.markdown());
        }
        out
    }

    /// Checks every struct a registered kind uploads (its `layouts`, see
    /// [`crate::struct_layout!`]), and those hppm's shared tables and GPU helpers upload, against
    /// the WGSL struct each mirrors, composed with every scene def: the WGSL names checked, or
    /// every difference found. A pass's own test calls this.
    pub fn check_layouts(&self) -> Result<Vec<&'static str>, Vec<String>> {
        let mut defs = super::all_scene_defs(&self.bsdfs);
        defs.extend(defs_of(["FLOAT_TEXELS"]));
        let library =
            ShaderLibrary::new(true, defs, &self.modules()).map_err(|e| vec![e.to_string()])?;
        let shared = super::hit_points::LAYOUTS
            .iter()
            .chain(crate::gpu_scene::resources::LAYOUTS)
            .chain(crate::gpu::radix_sort::LAYOUTS)
            .chain(crate::gpu::odd_iterations::LAYOUTS);
        let mut problems = Vec::new();
        let mut checked = Vec::new();
        for layout in self.kinds.iter().flat_map(|k| k.layouts).chain(shared) {
            match library.compose(&layout.shader) {
                Ok(module) => match layout.check(&module) {
                    Ok(()) => checked.push(layout.wgsl),
                    Err(e) => problems.push(e),
                },
                Err(e) => problems.push(format!("{}: {e}", layout.shader.path)),
            }
        }
        if problems.is_empty() {
            Ok(checked)
        } else {
            Err(problems)
        }
    }
}
