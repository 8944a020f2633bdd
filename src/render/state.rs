//! Render state on disk: a shard's accumulators (for `hppm merge`) and checkpoints (for
//! `hppm render --resume`), in one documented binary format.
//!
//! # Format (version 1)
//! ```text
//! bytes 0..8     magic "HPPMST01"
//! bytes 8..16    u64 little-endian: length H of the header
//! bytes 16..16+H the header: UTF-8 RON text of `StateHeader` (human-readable with `head -c`)
//! then           the sections' bytes, back to back in the header's order, each exactly as
//!                long as the header says
//! ```
//! A section is a GPU buffer as it was read back: for image accumulators, per pixel four
//! little-endian f32 (RGB sum, sample count), row-major from the top left. Shards hold the
//! accumulators whose per-pixel means add up to the image (`terms`); checkpoints hold every
//! buffer whose contents carry between iterations. Counts that grow with the render (iterations,
//! samples per pixel, photons) are u64 in the header.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::Error;
use crate::image::Image;
use crate::render::{Renderer, Term};

const MAGIC: &[u8; 8] = b"HPPMST01";
pub const FORMAT_VERSION: u32 = 1;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum StateKind {
    /// A shard's accumulators, for `hppm merge`.
    Shard,
    /// A render's full state, for `hppm render --resume`.
    Checkpoint,
}

/// One section's name and length in bytes.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Section {
    pub name: String,
    pub bytes: u64,
}

/// What a state file says about the render it comes from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StateHeader {
    pub version: u32,
    pub kind: StateKind,
    pub hppm: String,
    /// The scene file, for messages; `scene_hash` is what must match.
    pub scene: String,
    pub scene_hash: u64,
    pub graph: String,
    pub graph_hash: u64,
    pub seed: u64,
    pub width: u32,
    pub height: u32,
    /// This render runs global iterations shard, shard + shards, ...; (0, 1) when unsharded.
    pub shard: u64,
    pub shards: u64,
    /// Global iterations of the whole render's budget, when it counts iterations (--spp,
    /// --photons); `None` for a time budget.
    pub total_iterations: Option<u64>,
    /// Iterations this render has run.
    pub iterations: u64,
    pub samples_per_pixel: u64,
    pub photons: u64,
    pub sections: Vec<Section>,
}

/// A state file in memory: its header and its sections' bytes.
#[derive(Debug, Clone, PartialEq)]
pub struct StateFile {
    pub header: StateHeader,
    pub data: Vec<Vec<u8>>,
}

fn bad(path: &Path, message: impl std::fmt::Display) -> Error {
    Error::Other(format!("{}: {message}", path.display()))
}

impl StateFile {
    /// A file of `kind` for `header` (its `sections` are filled in from `sections`).
    pub fn new(mut header: StateHeader, sections: Vec<(String, Vec<u8>)>) -> Self {
        header.sections = sections
            .iter()
            .map(|(name, bytes)| Section {
                name: name.clone(),
                bytes: bytes.len() as u64,
            })
            .collect();
        Self {
            header,
            data: sections.into_iter().map(|(_, b)| b).collect(),
        }
    }

    pub fn to_bytes(&self) -> Result<Vec<u8>, Error> {
        let text = ron::ser::to_string_pretty(&self.header, ron::ser::PrettyConfig::default())
            .map_err(|e| Error::Other(format!("state header: {e}")))?;
        let mut out =
            Vec::with_capacity(16 + text.len() + self.data.iter().map(Vec::len).sum::<usize>());
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&(text.len() as u64).to_le_bytes());
        out.extend_from_slice(text.as_bytes());
        for section in &self.data {
            out.extend_from_slice(section);
        }
        Ok(out)
    }

    /// Written to a temporary file and renamed over `path`: a reader (or a pre-empted job)
    /// sees the old file or the new one, never half of one.
    pub fn write(&self, path: &Path) -> Result<(), Error> {
        crate::image::write_file_atomically(path, &self.to_bytes()?)
    }

    pub fn read(path: &Path) -> Result<Self, Error> {
        let bytes = std::fs::read(path).map_err(|e| bad(path, e))?;
        Self::from_bytes(path, &bytes)
    }

    /// Parses a state file; `path` names it in errors.
    pub fn from_bytes(path: &Path, bytes: &[u8]) -> Result<Self, Error> {
        if bytes.len() < 16 || &bytes[..8] != MAGIC {
            return Err(bad(
                path,
                "not an hppm shard or checkpoint (no HPPMST01 magic at its start)",
            ));
        }
        let mut len = [0u8; 8];
        len.copy_from_slice(&bytes[8..16]);
        let header_len = u64::from_le_bytes(len);
        let body = &bytes[16..];
        let header_end = usize::try_from(header_len)
            .ok()
            .filter(|&n| n <= body.len())
            .ok_or_else(|| bad(path, "truncated: its header runs past the end of the file"))?;
        let text = std::str::from_utf8(&body[..header_end])
            .map_err(|e| bad(path, format!("header is not UTF-8: {e}")))?;
        let header: StateHeader = ron::from_str(text).map_err(|e| {
            bad(
                path,
                format!(
                    "header line {}, column {}: {}",
                    e.span.start.line, e.span.start.col, e.code
                ),
            )
        })?;
        if header.version != FORMAT_VERSION {
            return Err(bad(
                path,
                format!(
                    "field version: format {} (this hppm reads {FORMAT_VERSION})",
                    header.version
                ),
            ));
        }
        let mut data = Vec::new();
        let mut at = header_end;
        for section in &header.sections {
            let end = usize::try_from(section.bytes)
                .ok()
                .and_then(|n| at.checked_add(n))
                .filter(|&end| end <= body.len())
                .ok_or_else(|| {
                    bad(
                        path,
                        format!("truncated: section {} runs past the end", section.name),
                    )
                })?;
            data.push(body[at..end].to_vec());
            at = end;
        }
        if at != body.len() {
            return Err(bad(
                path,
                format!("{} bytes after the last section", body.len() - at),
            ));
        }
        Ok(Self { header, data })
    }

    /// The sections by name, with their bytes.
    pub fn sections(&self) -> Vec<(String, Vec<u8>)> {
        self.header
            .sections
            .iter()
            .map(|s| s.name.clone())
            .zip(self.data.iter().cloned())
            .collect()
    }
}

/// Where a render's scene and graph came from, and the budget it runs to: what a state file
/// records besides the renderer's own state.
#[derive(Debug, Clone)]
pub struct Origin {
    pub scene: String,
    pub graph: String,
    pub graph_hash: u64,
    pub total_iterations: Option<u64>,
}

fn header_of(kind: StateKind, r: &Renderer<'_>, origin: &Origin) -> StateHeader {
    let schedule = r.schedule();
    let (width, height) = r.size();
    StateHeader {
        version: FORMAT_VERSION,
        kind,
        hppm: env!("CARGO_PKG_VERSION").into(),
        scene: origin.scene.clone(),
        scene_hash: r.scene_hash(),
        graph: origin.graph.clone(),
        graph_hash: origin.graph_hash,
        seed: r.seed(),
        width,
        height,
        shard: schedule.first,
        shards: schedule.stride,
        total_iterations: origin.total_iterations,
        iterations: r.iterations(),
        samples_per_pixel: r.samples_per_pixel(),
        photons: r.photons(),
        sections: Vec::new(),
    }
}

/// A shard's accumulators, for `hppm merge`.
pub fn shard_file(r: &Renderer<'_>, origin: &Origin) -> Result<StateFile, Error> {
    let sections = r
        .read_terms()?
        .into_iter()
        .map(|(name, sums)| (name, bytemuck::cast_slice(&sums).to_vec()))
        .collect();
    Ok(StateFile::new(
        header_of(StateKind::Shard, r, origin),
        sections,
    ))
}

/// A render's full state, for `hppm render --resume`.
pub fn checkpoint_file(r: &Renderer<'_>, origin: &Origin) -> Result<StateFile, Error> {
    Ok(StateFile::new(
        header_of(StateKind::Checkpoint, r, origin),
        r.read_state()?,
    ))
}

/// Puts the checkpoint at `path` back into `r`, a renderer made for the same scene, graph,
/// seed, size and shard; refuses one made for another, naming the field.
pub fn resume(
    r: &mut Renderer<'_>,
    origin: &Origin,
    path: &Path,
    file: &StateFile,
) -> Result<(), Error> {
    let h = &file.header;
    if h.kind != StateKind::Checkpoint {
        return Err(bad(
            path,
            "is a shard, not a checkpoint (merge it with hppm merge)",
        ));
    }
    let ours = header_of(StateKind::Checkpoint, r, origin);
    let differs = |field: &str, theirs: String, now: String| {
        Err(bad(
            path,
            format!("field {field} is {theirs} in the checkpoint but {now} for this render"),
        ))
    };
    if h.scene_hash != ours.scene_hash {
        return differs(
            "scene_hash (the scene, or its size)",
            format!(
                "{:016x} ({}, {}x{})",
                h.scene_hash, h.scene, h.width, h.height
            ),
            format!(
                "{:016x} ({}, {}x{})",
                ours.scene_hash, ours.scene, ours.width, ours.height
            ),
        );
    }
    if h.graph_hash != ours.graph_hash {
        return differs(
            "graph_hash (the graph)",
            format!("{:016x} ({})", h.graph_hash, h.graph),
            format!("{:016x} ({})", ours.graph_hash, ours.graph),
        );
    }
    if h.seed != ours.seed {
        return differs("seed", h.seed.to_string(), ours.seed.to_string());
    }
    if (h.shard, h.shards) != (ours.shard, ours.shards) {
        return differs(
            "shard",
            format!("{}/{}", h.shard, h.shards),
            format!("{}/{}", ours.shard, ours.shards),
        );
    }
    r.restore_state(h.iterations, &file.sections())
        .map_err(|e| bad(path, e))
}

/// What `merge` made of a set of shards.
#[derive(Debug, Clone)]
pub struct Merged {
    pub image: Image,
    /// The summed accumulators, by name, as per-pixel sums and counts.
    pub terms: Vec<Term>,
    pub shards: Vec<u64>,
    pub of: u64,
    pub samples_per_pixel: u64,
    pub photons: u64,
    pub header: StateHeader,
}

/// Checks that `shards` (each with the file it came from) are shards of one render, every one
/// once and none missing unless `partial`, and sums their accumulators into its image.
pub fn merge(shards: &[(PathBuf, StateFile)], partial: bool) -> Result<Merged, Error> {
    let Some((first_path, first)) = shards.first() else {
        return Err(Error::Other("merge: no shard files given".into()));
    };
    let mut seen: BTreeMap<u64, &Path> = BTreeMap::new();
    for (path, file) in shards {
        let h = &file.header;
        if h.kind != StateKind::Shard {
            return Err(bad(
                path,
                "is a checkpoint, not a shard (a render resumes from it)",
            ));
        }
        let f = &first.header;
        let mismatch = |field: &str, ours: String, theirs: String| {
            Err(Error::Other(format!(
                "{} does not belong with {}: field {field} is {ours} there and {theirs} here",
                path.display(),
                first_path.display()
            )))
        };
        if h.scene_hash != f.scene_hash {
            return mismatch(
                "scene_hash (the scene, or its size)",
                format!("{:016x} ({})", f.scene_hash, f.scene),
                format!("{:016x} ({})", h.scene_hash, h.scene),
            );
        }
        if h.graph_hash != f.graph_hash {
            return mismatch(
                "graph_hash (the graph)",
                format!("{:016x} ({})", f.graph_hash, f.graph),
                format!("{:016x} ({})", h.graph_hash, h.graph),
            );
        }
        if h.seed != f.seed {
            return mismatch("seed", f.seed.to_string(), h.seed.to_string());
        }
        if (h.width, h.height) != (f.width, f.height) {
            return mismatch(
                "width x height",
                format!("{}x{}", f.width, f.height),
                format!("{}x{}", h.width, h.height),
            );
        }
        if h.shards != f.shards {
            return mismatch(
                "shards (n of shard k of n)",
                f.shards.to_string(),
                h.shards.to_string(),
            );
        }
        if h.total_iterations != f.total_iterations {
            let show = |t: Option<u64>| t.map_or("a time budget".into(), |t| t.to_string());
            return mismatch(
                "total_iterations (the budget)",
                show(f.total_iterations),
                show(h.total_iterations),
            );
        }
        let names = |h: &StateHeader| {
            h.sections
                .iter()
                .map(|s| format!("{}:{}", s.name, s.bytes))
                .collect::<Vec<_>>()
                .join(", ")
        };
        if names(h) != names(f) {
            return mismatch("sections", names(f), names(h));
        }
        if h.shard >= h.shards {
            return Err(bad(
                path,
                format!("field shard: {} is not below shards {}", h.shard, h.shards),
            ));
        }
        if let Some(other) = seen.insert(h.shard, path) {
            return Err(Error::Other(format!(
                "shard {} of {} is given twice: {} and {}",
                h.shard,
                h.shards,
                other.display(),
                path.display()
            )));
        }
    }
    let header = &first.header;
    let missing: Vec<String> = (0..header.shards)
        .filter(|k| !seen.contains_key(k))
        .map(|k| k.to_string())
        .collect();
    if !missing.is_empty() && !partial {
        return Err(Error::Other(format!(
            "shards {} of {} are missing (give every shard, or merge those present as a partial render)",
            missing.join(", "),
            header.shards
        )));
    }
    let pixels = header.width as usize * header.height as usize;
    let mut terms = Vec::new();
    for (index, section) in header.sections.iter().enumerate() {
        if section.bytes != pixels as u64 * 16 {
            return Err(bad(
                first_path,
                format!(
                    "section {} has {} bytes, not 16 per pixel of {}x{}",
                    section.name, section.bytes, header.width, header.height
                ),
            ));
        }
        let mut sum = vec![[0.0f64; 4]; pixels];
        for (_, file) in shards {
            let values: &[[f32; 4]] = bytemuck::try_cast_slice(&file.data[index])
                .map_err(|e| Error::Other(format!("section {}: {e}", section.name)))?;
            for (s, v) in sum.iter_mut().zip(values) {
                for c in 0..4 {
                    s[c] += v[c] as f64;
                }
            }
        }
        let sum: Vec<[f32; 4]> = sum.iter().map(|s| s.map(|v| v as f32)).collect();
        terms.push((section.name.clone(), sum));
    }
    let mut image = Image::from_sums(header.width, header.height, &vec![[0.0; 4]; pixels]);
    for (_, sums) in &terms {
        let term = Image::from_sums(header.width, header.height, sums);
        for (p, t) in image.pixels.iter_mut().zip(&term.pixels) {
            for c in 0..3 {
                p[c] += t[c];
            }
        }
    }
    Ok(Merged {
        image,
        terms,
        shards: seen.keys().copied().collect(),
        of: header.shards,
        samples_per_pixel: shards.iter().map(|(_, f)| f.header.samples_per_pixel).sum(),
        photons: shards.iter().map(|(_, f)| f.header.photons).sum(),
        header: header.clone(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(kind: StateKind, shard: u64) -> StateHeader {
        StateHeader {
            version: FORMAT_VERSION,
            kind,
            hppm: "test".into(),
            scene: "a.xml".into(),
            scene_hash: 11,
            graph: "g.ron".into(),
            graph_hash: 22,
            seed: 3,
            width: 2,
            height: 1,
            shard,
            shards: 3,
            total_iterations: Some(9),
            iterations: 3,
            samples_per_pixel: 3,
            photons: 1 << 40,
            sections: Vec::new(),
        }
    }

    fn shard(k: u64, value: f32) -> (PathBuf, StateFile) {
        let pixels: Vec<[f32; 4]> = vec![[value, 2.0 * value, 0.0, 1.0], [0.0, 0.0, 0.0, 0.0]];
        let file = StateFile::new(
            header(StateKind::Shard, k),
            vec![(
                "camera.radiance".into(),
                bytemuck::cast_slice(&pixels).to_vec(),
            )],
        );
        (PathBuf::from(format!("shard{k}.hppm")), file)
    }

    /// A file reads back as written; a truncated or foreign one is refused with its name.
    #[test]
    fn state_files_round_trip_and_refuse_damage() {
        let (_, file) = shard(1, 0.5);
        let bytes = file.to_bytes().expect("bytes");
        let path = Path::new("x.hppm");
        assert_eq!(StateFile::from_bytes(path, &bytes).expect("parse"), file);
        let cut = StateFile::from_bytes(path, &bytes[..bytes.len() - 1]).unwrap_err();
        assert!(cut.to_string().contains("x.hppm: truncated"), "{cut}");
        let foreign = StateFile::from_bytes(path, b"P6 not a state file").unwrap_err();
        assert!(foreign.to_string().contains("magic"), "{foreign}");
    }

    /// Sums and counts add; the image is the mean of the summed accumulator; a pixel with no
    /// samples stays 0; photon totals add in u64 past 2^32.
    #[test]
    fn merge_sums_accumulators() {
        let shards = vec![shard(0, 1.0), shard(1, 2.0), shard(2, 6.0)];
        let merged = merge(&shards, false).expect("merge");
        assert_eq!(merged.terms[0].1[0], [9.0, 18.0, 0.0, 3.0]);
        assert_eq!(merged.image.pixels[0], [3.0, 6.0, 0.0]);
        assert_eq!(merged.image.pixels[1], [0.0; 3]);
        assert_eq!(merged.photons, 3 << 40);
    }

    /// Each refusal names what is wrong: the field that differs, the shard given twice, the
    /// shards missing, a checkpoint among shards.
    #[test]
    fn merge_refuses_shards_of_different_renders() {
        let refuse = |shards: Vec<(PathBuf, StateFile)>, partial: bool| {
            merge(&shards, partial).unwrap_err().to_string()
        };
        let alter = |f: &dyn Fn(&mut StateHeader)| {
            let mut s = shard(1, 2.0);
            f(&mut s.1.header);
            vec![shard(0, 1.0), s, shard(2, 3.0)]
        };
        type Change<'a> = &'a dyn Fn(&mut StateHeader);
        let cases: [(Change, &str); 5] = [
            (&|h| h.scene_hash = 12, "field scene_hash"),
            (&|h| h.graph_hash = 0, "field graph_hash"),
            (&|h| h.seed = 4, "field seed"),
            (&|h| h.shards = 4, "field shards"),
            (&|h| h.total_iterations = Some(10), "field total_iterations"),
        ];
        for (change, expected) in cases {
            let message = refuse(alter(change), false);
            assert!(message.contains(expected), "{message}");
            assert!(message.contains("shard1.hppm"), "{message}");
        }
        let twice = refuse(vec![shard(0, 1.0), shard(1, 1.0), shard(1, 1.0)], false);
        assert!(twice.contains("shard 1 of 3 is given twice"), "{twice}");
        let missing = refuse(vec![shard(0, 1.0), shard(2, 1.0)], false);
        assert!(missing.contains("shards 1 of 3 are missing"), "{missing}");
        assert!(merge(&[shard(0, 1.0), shard(2, 1.0)], true).is_ok());
        let mut checkpoint = shard(2, 1.0);
        checkpoint.1.header.kind = StateKind::Checkpoint;
        let message = refuse(vec![shard(0, 1.0), shard(1, 1.0), checkpoint], false);
        assert!(message.contains("is a checkpoint"), "{message}");
    }
}
