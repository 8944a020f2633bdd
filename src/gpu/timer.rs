//! Per-node GPU time from timestamp queries written between a node's commands.

use super::{GpuContext, GpuError};

/// Two timestamps per node (before its first command, after its last), resolved and read back
/// once per iteration. Needs TIMESTAMP_QUERY_INSIDE_ENCODERS: nodes record several compute
/// passes (and copies), so only encoder-level timestamps bracket all of a node's work.
pub struct NodeTimer {
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    nodes: u32,
    seconds_per_tick: f64,
}

impl NodeTimer {
    /// `None` when the adapter cannot write timestamps inside command encoders.
    pub fn new(gpu: &GpuContext, nodes: usize) -> Result<Option<Self>, GpuError> {
        let needed =
            wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS;
        if !gpu.features.contains(needed) || nodes == 0 {
            return Ok(None);
        }
        let nodes = nodes as u32;
        let queries = gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("node timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count: 2 * nodes,
        });
        let resolved = gpu.create_buffer(
            "node timestamps resolved",
            16 * nodes as u64,
            wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
        )?;
        Ok(Some(Self {
            queries,
            resolved,
            nodes,
            seconds_per_tick: gpu.queue.get_timestamp_period() as f64 * 1e-9,
        }))
    }

    pub fn begin(&self, encoder: &mut wgpu::CommandEncoder, node: usize) {
        encoder.write_timestamp(&self.queries, 2 * node as u32);
    }

    pub fn end(&self, encoder: &mut wgpu::CommandEncoder, node: usize) {
        encoder.write_timestamp(&self.queries, 2 * node as u32 + 1);
    }

    /// Records the copy of this iteration's timestamps into the readable buffer.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.resolve_query_set(&self.queries, 0..2 * self.nodes, &self.resolved, 0);
    }

    /// Seconds between each node's two timestamps, by node index (after `resolve` was
    /// submitted); meaningful for the nodes that ran this iteration.
    pub fn read(&self, gpu: &GpuContext) -> Result<Vec<f64>, GpuError> {
        let ticks: Vec<[u64; 2]> = gpu.read_pod(&self.resolved, self.nodes as usize)?;
        Ok(ticks
            .iter()
            .map(|[begin, end]| end.saturating_sub(*begin) as f64 * self.seconds_per_tick)
            .collect())
    }
}
