//! Owned Vulkan objects (pipelines, layouts, pools, samplers, query pools, …): each is destroyed
//! when its [`Owned`] handle drops, and keeps its [`Context`] alive until then, so no owner keeps
//! a hand-written list of objects to destroy.

use super::context::Context;
use ash::vk;
use std::sync::Arc;

/// A Vulkan object destroyed with the device that made it.
pub trait DeviceObject: vk::Handle + Copy {
    /// Destroys the object.
    ///
    /// # Safety
    /// The object was created on `device` and is no longer in use by the GPU.
    unsafe fn destroy(self, device: &ash::Device);
}

macro_rules! device_object {
    ($($ty:ty => $f:ident),+ $(,)?) => {
        $(impl DeviceObject for $ty {
            unsafe fn destroy(self, device: &ash::Device) {
                unsafe { device.$f(self, None) }
            }
        })+
    };
}

device_object!(
    vk::Pipeline => destroy_pipeline,
    vk::PipelineLayout => destroy_pipeline_layout,
    vk::DescriptorSetLayout => destroy_descriptor_set_layout,
    vk::DescriptorPool => destroy_descriptor_pool,
    vk::Sampler => destroy_sampler,
    vk::QueryPool => destroy_query_pool,
    vk::ShaderModule => destroy_shader_module,
    vk::PipelineCache => destroy_pipeline_cache,
    vk::Semaphore => destroy_semaphore,
    vk::Fence => destroy_fence,
);

/// An owned Vulkan object (pipeline, layout, pool, sampler, …), destroyed when dropped.
pub struct Owned<H: DeviceObject> {
    ctx: Arc<Context>,
    raw: H,
}

impl<H: DeviceObject> Owned<H> {
    /// Takes ownership of `raw`, created on `ctx`'s device, and names it.
    pub fn new(ctx: &Arc<Context>, raw: H, name: &str) -> Self {
        ctx.name(raw, name);
        Self {
            ctx: ctx.clone(),
            raw,
        }
    }

    /// The handle.
    pub fn raw(&self) -> H {
        self.raw
    }
}

impl<H: DeviceObject> Drop for Owned<H> {
    fn drop(&mut self) {
        if !self.raw.is_null() {
            unsafe { self.raw.destroy(&self.ctx.device) };
        }
    }
}
