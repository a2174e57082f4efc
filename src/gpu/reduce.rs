//! The convergence monitor's figures reduced on the GPU (`glsl/reduce.comp`): after every
//! iteration of a batch, two compute dispatches turn the leaves' old and new I_ex into four
//! numbers in one slot of a host-visible buffer, so a batch of iterations is one submission and
//! one fence wait, and 16 bytes per iteration come back instead of the tables. The asymmetric
//! scheme's several propagations per iteration overwrite the ping-pong image that held the
//! iteration's start, so that start is copied into a snapshot first.

use super::barrier::{transition, Access};
use super::context::Context;
use super::handle::Owned;
use super::layout::as_bytes;
use super::memory::{Buffer, Image, ImageDesc, Purpose};
use super::pipelines::{self, Layouts};
use super::profiler::{label_begin, label_end};
use super::resources::Resources;
use crate::error::Result;
use ash::vk;
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// Workgroups of the first stage (each reduces a stride of texels into one partial).
const GROUPS: u32 = 64;

/// Slots of the result buffer: the largest batch.
pub const MAX_BATCH: usize = 64;

/// Push constants of `reduce.comp` (`ReduceConstants` there).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
struct ReduceConstants {
    bins: u32,
    rows_per_column: u32,
    pad: u32,
    rows: u32,
    width: u32,
    stage: u32,
    slot: u32,
    groups: u32,
}

/// Sums of one iteration, as reduced (scaled like the tables).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reduced {
    /// Σ |new − old|² over the leaves' texels.
    pub diff2: f64,
    /// Σ |new|² over the leaves' texels.
    pub norm2: f64,
    /// Σ over the leaves' front bins of the mean of RGB (flux before ×ω).
    pub flux: f64,
    /// Largest |new| (3e38 when a value is not finite).
    pub peak: f64,
}

/// Where an iteration's start state is read from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Start {
    /// The other image of the ping-pong pair (one propagation per iteration).
    PingPong,
    /// The snapshot taken by [`Reducer::record_snapshot`].
    Snapshot,
}

/// The reduction's pipeline, buffers and descriptor sets.
pub struct Reducer {
    ctx: Arc<Context>,
    pipeline: Owned<vk::Pipeline>,
    layouts: Layouts,
    _pool: Owned<vk::DescriptorPool>,
    sampler: Owned<vk::Sampler>,
    /// `sets[start][new parity]`.
    sets: [[vk::DescriptorSet; 2]; 2],
    partials: Buffer,
    results: Buffer,
    snapshot: Option<Image>,
}

const KINDS: [vk::DescriptorType; 7] = [
    vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
    vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
    vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
    vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
    vk::DescriptorType::STORAGE_BUFFER,
    vk::DescriptorType::STORAGE_BUFFER,
    vk::DescriptorType::STORAGE_BUFFER,
];

impl Reducer {
    /// Creates the reduction for `res`'s tables.
    pub fn new(ctx: &Arc<Context>, res: &Resources) -> Result<Self> {
        let layouts = Layouts::with_stages(
            ctx,
            "reduce",
            &KINDS,
            std::mem::size_of::<ReduceConstants>() as u32,
            vk::ShaderStageFlags::COMPUTE,
        )?;
        let pipeline = pipelines::create_compute(ctx, &layouts.pipeline, "reduce.comp")?;
        let pool = pipelines::descriptor_pool(ctx, &KINDS, 4, "reduce descriptor pool")?;
        let sampler = pipelines::texel_sampler(ctx, "reduce sampler")?;
        let partials = Buffer::new(
            ctx,
            "reduce partials",
            GROUPS as u64 * 16,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::GpuOnly,
        )?;
        let results = Buffer::new(
            ctx,
            "reduce results",
            MAX_BATCH as u64 * 16,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::GpuToCpu,
        )?;
        let mut sets = [[vk::DescriptorSet::null(); 2]; 2];
        for row in sets.iter_mut() {
            for s in row.iter_mut() {
                *s = pipelines::allocate_set(ctx, &pool, &layouts.set, "reduce set")?;
            }
        }
        let r = Self {
            ctx: ctx.clone(),
            pipeline,
            layouts,
            _pool: pool,
            sampler,
            sets,
            partials,
            results,
            snapshot: None,
        };
        for p in 0..2 {
            r.write(res, Start::PingPong, p);
        }
        Ok(r)
    }

    fn write(&self, res: &Resources, start: Start, new: usize) {
        let im = &res.images;
        let old = match (start, &self.snapshot) {
            (Start::Snapshot, Some(s)) => s.view,
            _ => im.leaf_ex(1 - new).view,
        };
        let images = [
            (0, old),
            (1, im.leaf_ex(new).view),
            (2, im.attr_normal_area.view),
            (3, im.attr_leaf.view),
        ];
        let buffers = [
            (4, res.buffers.bin_centers.raw),
            (5, self.partials.raw),
            (6, self.results.raw),
        ];
        let set = self.sets[(start == Start::Snapshot) as usize][new];
        pipelines::write_set(&self.ctx, set, self.sampler.raw(), &images, &buffers);
    }

    /// Records a copy of the leaves' I_ex of parity `p` into the snapshot (the start of an
    /// iteration with several propagations), creating it on first use.
    pub fn record_snapshot(
        &mut self,
        cmd: vk::CommandBuffer,
        res: &mut Resources,
        p: usize,
    ) -> Result<()> {
        if self.snapshot.is_none() {
            let d = &res.images.leaf_ex0.desc;
            let desc = ImageDesc::new(
                "I_ex at the iteration's start",
                d.width,
                d.height,
                d.format,
                Purpose::Tables,
            );
            self.snapshot = Some(desc.create(&self.ctx)?);
            for new in 0..2 {
                self.write(res, Start::Snapshot, new);
            }
        }
        let snap = self.snapshot.as_mut().expect("created above");
        let src = res.images.leaf_ex_mut(p);
        transition(
            &self.ctx,
            cmd,
            &mut [
                (&mut *src, Access::TransferSrc),
                (&mut *snap, Access::TransferDst),
            ],
        );
        let layers = vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        };
        let region = vk::ImageCopy::default()
            .src_subresource(layers)
            .dst_subresource(layers)
            .extent(vk::Extent3D {
                width: src.extent.width,
                height: src.extent.height,
                depth: 1,
            });
        unsafe {
            self.ctx.device.cmd_copy_image(
                cmd,
                src.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                snap.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
            )
        };
        transition(
            &self.ctx,
            cmd,
            &mut [(src, Access::Sampled), (snap, Access::Sampled)],
        );
        Ok(())
    }

    /// Records the reduction of the iteration that ended with leaves' parity `new` into `slot`.
    pub fn record(
        &mut self,
        cmd: vk::CommandBuffer,
        res: &mut Resources,
        start: Start,
        new: usize,
        slot: usize,
    ) {
        let d = &self.ctx.device;
        let layout = *res.layout();
        let im = &mut res.images;
        let (a, b) = if new == 0 {
            (&mut im.leaf_ex0, &mut im.leaf_ex1)
        } else {
            (&mut im.leaf_ex1, &mut im.leaf_ex0)
        };
        let mut list = vec![
            (a, Access::Sampled),
            (&mut im.attr_normal_area, Access::Sampled),
            (&mut im.attr_leaf, Access::Sampled),
        ];
        if start == Start::PingPong {
            list.push((b, Access::Sampled));
        }
        transition(&self.ctx, cmd, &mut list);
        label_begin(&self.ctx, cmd, "reduce");
        let set = self.sets[(start == Start::Snapshot) as usize][new];
        let mut c = ReduceConstants {
            bins: layout.bins,
            rows_per_column: layout.rows_per_column,
            pad: 0,
            rows: layout.rows,
            width: layout.width(),
            stage: 0,
            slot: slot as u32,
            groups: GROUPS,
        };
        let pl = self.layouts.pipeline.raw();
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.pipeline.raw());
            d.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::COMPUTE, pl, 0, &[set], &[]);
            for (stage, groups) in [(0u32, GROUPS), (1, 1)] {
                c.stage = stage;
                let bytes = as_bytes(std::slice::from_ref(&c));
                d.cmd_push_constants(cmd, pl, vk::ShaderStageFlags::COMPUTE, 0, bytes);
                d.cmd_dispatch(cmd, groups, 1, 1);
                // Partials written → read by stage 1; results written → read by the host.
                let mb = [vk::MemoryBarrier2::default()
                    .src_stage_mask(vk::PipelineStageFlags2::COMPUTE_SHADER)
                    .src_access_mask(vk::AccessFlags2::SHADER_STORAGE_WRITE)
                    .dst_stage_mask(
                        vk::PipelineStageFlags2::COMPUTE_SHADER | vk::PipelineStageFlags2::HOST,
                    )
                    .dst_access_mask(
                        vk::AccessFlags2::SHADER_STORAGE_READ
                            | vk::AccessFlags2::SHADER_STORAGE_WRITE
                            | vk::AccessFlags2::HOST_READ,
                    )];
                d.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&mb));
            }
        }
        label_end(&self.ctx, cmd);
    }

    /// The sums in slots `0..n` (after the submission that recorded them completed).
    pub fn read(&self, n: usize) -> Result<Vec<Reduced>> {
        let bytes = self.results.mapped()?;
        Ok(bytes
            .chunks_exact(16)
            .take(n)
            .map(|c| {
                let f =
                    |i: usize| f32::from_le_bytes(c[4 * i..4 * i + 4].try_into().unwrap()) as f64;
                Reduced {
                    diff2: f(0),
                    norm2: f(1),
                    flux: f(2),
                    peak: f(3),
                }
            })
            .collect())
    }

    /// Bytes read back per iteration.
    pub const BYTES_PER_ITERATION: usize = 16;
}
