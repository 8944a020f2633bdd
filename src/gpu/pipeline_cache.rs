//! Compute pipelines and bind group layouts kept for the life of a device, so that a second
//! renderer of the same scene (another seed, a shard, the next run of a benchmark, a host program
//! rendering again) neither composes its shaders again nor asks the driver to compile them:
//! on lavapipe each pipeline costs a SPIR-V to NIR translation and a cache lookup even when Mesa's
//! shader cache holds it, about half of a small render's setup.
//!
//! Layouts are kept by their entries, so equal layouts are one handle and a pipeline can be
//! keyed by the handles of its layouts: a bind group made from a layout handed out here fits
//! every pipeline built with it.

use std::collections::HashMap;
use std::sync::Mutex;

/// What a compute pipeline is built from: the shader library it was composed in (its modules'
/// text, defs and device features, as one fingerprint), the entry file's path and text, the
/// pass's own defs, the entry point and the bind group layouts.
#[derive(Clone, PartialEq, Eq, Hash)]
pub struct PipelineKey {
    pub library: u64,
    pub path: String,
    pub source: String,
    pub extra: Vec<String>,
    pub entry: String,
    pub layouts: Vec<wgpu::BindGroupLayout>,
}

const MAX_PIPELINES: usize = 512;

#[derive(Default)]
pub struct PipelineCache {
    pipelines: Mutex<HashMap<PipelineKey, wgpu::ComputePipeline>>,
    layouts: Mutex<HashMap<Vec<wgpu::BindGroupLayoutEntry>, wgpu::BindGroupLayout>>,
}

impl PipelineCache {
    /// The layout for `entries`: the one made earlier for the same entries, or a new one.
    pub fn layout(
        &self,
        device: &wgpu::Device,
        label: &str,
        entries: &[wgpu::BindGroupLayoutEntry],
    ) -> wgpu::BindGroupLayout {
        let make = || {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries,
            })
        };
        // A poisoned lock (a panic elsewhere while it was held) only costs the sharing.
        let Ok(mut layouts) = self.layouts.lock() else {
            return make();
        };
        layouts.entry(entries.to_vec()).or_insert_with(make).clone()
    }

    /// The pipeline built for `key` before, or the one `build` makes now (kept when it
    /// succeeds). Only layouts from [`PipelineCache::layout`] are worth keying on: another
    /// layout is a new handle each time, so its pipelines are built and not kept.
    pub fn pipeline<E>(
        &self,
        key: PipelineKey,
        build: impl FnOnce() -> Result<wgpu::ComputePipeline, E>,
    ) -> Result<wgpu::ComputePipeline, E> {
        if !self.all_shared(&key.layouts) {
            return build();
        }
        if let Some(found) = self
            .pipelines
            .lock()
            .ok()
            .and_then(|p| p.get(&key).cloned())
        {
            return Ok(found);
        }
        let pipeline = build()?;
        if let Ok(mut pipelines) = self.pipelines.lock() {
            // A host rendering scene after scene keeps at most this many; a render needs a
            // few dozen.
            if pipelines.len() >= MAX_PIPELINES {
                pipelines.clear();
            }
            pipelines.insert(key, pipeline.clone());
        }
        Ok(pipeline)
    }

    fn all_shared(&self, layouts: &[wgpu::BindGroupLayout]) -> bool {
        let Ok(shared) = self.layouts.lock() else {
            return false;
        };
        layouts.iter().all(|l| shared.values().any(|s| s == l))
    }

    /// How many pipelines are kept (for tests).
    pub fn pipelines(&self) -> usize {
        self.pipelines.lock().map(|p| p.len()).unwrap_or(0)
    }
}
