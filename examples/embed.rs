//! Embedding antiradiance in a host application that owns the Vulkan instance, device, queue and
//! memory allocator: the host builds its scene in code (no files), hands device and scene to the
//! library, and per frame records the solver's iterations and the frame into its own command
//! buffer, submits it, and reads the result image back with its own allocator's buffer.
//!
//!     cargo run --release --example embed -- [--frames N] [--exr OUT.exr] [--png OUT.png]
//!
//! The validation layer is on; any validation message fails the run (exit status 1). Per frame
//! the block slides along keyframes the host gave it in code and the light moves
//! (`Engine::set_time`, `Engine::set_light`, `Engine::record_update`): the links were made for
//! the block's whole motion, so the update follows it in place and records its uploads into the
//! host's command buffer, and the solve continues from the previous frame's solution.

use antiradiance::engine::{Engine, Options, OutputImage};
use antiradiance::frame::Image;
use antiradiance::gpu::{Context, HostDevice};
use antiradiance::progress::Silent;
use antiradiance::scene::animation::ObjectKey;
use antiradiance::scene::{Light, Material, Scene};
use ash::vk;
use glam::{DMat4, DQuat, DVec3};
use gpu_allocator::vulkan::{
    Allocation, AllocationCreateDesc, AllocationScheme, Allocator, AllocatorCreateDesc,
};
use gpu_allocator::MemoryLocation;
use std::ffi::c_void;
use std::sync::atomic::{AtomicUsize, Ordering};

type Res<T> = Result<T, Box<dyn std::error::Error>>;

/// Validation messages seen (the run fails if any).
static MESSAGES: AtomicUsize = AtomicUsize::new(0);

unsafe extern "system" fn on_message(
    _: vk::DebugUtilsMessageSeverityFlagsEXT,
    _: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    _: *mut c_void,
) -> vk::Bool32 {
    if let Some(m) = unsafe { data.as_ref() }.and_then(|d| unsafe { d.message_as_c_str() }) {
        eprintln!("vulkan validation: {}", m.to_string_lossy());
    }
    MESSAGES.fetch_add(1, Ordering::SeqCst);
    vk::FALSE
}

/// The host's own Vulkan objects (an application would have these already).
struct Host {
    entry: ash::Entry,
    instance: ash::Instance,
    messenger: (ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT),
    physical_device: vk::PhysicalDevice,
    device: ash::Device,
    queue: vk::Queue,
    family: u32,
    rectangular_lines: bool,
    wide_lines: bool,
}

impl Host {
    /// Instance with the validation layer and a messenger; the first device with a graphics
    /// queue; the features the library needs (Vulkan 1.3 dynamic rendering and
    /// synchronization2, `independentBlend`; rectangular and wide lines where offered).
    fn new() -> Res<Self> {
        let entry = unsafe { ash::Entry::load()? };
        let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_3);
        let layers = [c"VK_LAYER_KHRONOS_validation".as_ptr()];
        let exts = [vk::EXT_DEBUG_UTILS_NAME.as_ptr()];
        let instance = unsafe {
            entry.create_instance(
                &vk::InstanceCreateInfo::default()
                    .application_info(&app)
                    .enabled_layer_names(&layers)
                    .enabled_extension_names(&exts),
                None,
            )?
        };
        let du = ash::ext::debug_utils::Instance::new(&entry, &instance);
        let messenger = unsafe {
            du.create_debug_utils_messenger(
                &vk::DebugUtilsMessengerCreateInfoEXT::default()
                    .message_severity(
                        vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
                            | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
                    )
                    .message_type(
                        vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                            | vk::DebugUtilsMessageTypeFlagsEXT::GENERAL,
                    )
                    .pfn_user_callback(Some(on_message)),
                None,
            )?
        };
        let (physical_device, family) = unsafe { instance.enumerate_physical_devices()? }
            .into_iter()
            .find_map(|pd| {
                let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
                families
                    .iter()
                    .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS))
                    .map(|q| (pd, q as u32))
            })
            .ok_or("no Vulkan device with a graphics queue")?;
        let has_lines = unsafe { instance.enumerate_device_extension_properties(physical_device)? }
            .iter()
            .any(|e| e.extension_name_as_c_str() == Ok(vk::EXT_LINE_RASTERIZATION_NAME));
        let mut lines = vk::PhysicalDeviceLineRasterizationFeaturesEXT::default();
        let mut f2 = vk::PhysicalDeviceFeatures2::default();
        if has_lines {
            f2 = f2.push_next(&mut lines);
        }
        unsafe { instance.get_physical_device_features2(physical_device, &mut f2) };
        // Wide lines let the solver draw a link's footprint in fewer lines (optional).
        let wide_lines = f2.features.wide_lines == vk::TRUE;
        let rectangular_lines = has_lines && lines.rectangular_lines == vk::TRUE;
        let mut f13 = vk::PhysicalDeviceVulkan13Features::default()
            .dynamic_rendering(true)
            .synchronization2(true);
        let mut en_lines =
            vk::PhysicalDeviceLineRasterizationFeaturesEXT::default().rectangular_lines(true);
        let core = vk::PhysicalDeviceFeatures::default()
            .independent_blend(true)
            .wide_lines(wide_lines);
        let prio = [1.0f32];
        let queues = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(family)
            .queue_priorities(&prio)];
        let dev_exts = [vk::EXT_LINE_RASTERIZATION_NAME.as_ptr()];
        let mut info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_features(&core)
            .push_next(&mut f13);
        if rectangular_lines {
            info = info
                .enabled_extension_names(&dev_exts)
                .push_next(&mut en_lines);
        }
        let device = unsafe { instance.create_device(physical_device, &info, None)? };
        let queue = unsafe { device.get_device_queue(family, 0) };
        Ok(Self {
            entry,
            instance,
            messenger: (du, messenger),
            physical_device,
            device,
            queue,
            family,
            rectangular_lines,
            wide_lines,
        })
    }
}

impl Drop for Host {
    fn drop(&mut self) {
        unsafe {
            self.device.destroy_device(None);
            self.messenger
                .0
                .destroy_debug_utils_messenger(self.messenger.1, None);
            self.instance.destroy_instance(None);
        }
    }
}

/// The moving block's object index (the scene's first object).
const BLOCK: usize = 0;
/// Where the point light starts.
const LIGHT: DVec3 = DVec3::new(0.2, 1.7, 0.5);

/// Adds the quad `p` (counter-clockwise seen from its front) as two triangles.
fn quad(s: &mut Scene, name: &str, p: [DVec3; 4], material: u32) {
    s.add_mesh(name, p.to_vec(), vec![[0, 1, 2], [0, 2, 3]], material);
}

/// The host's own scene data: an open room (floor, back, red left and green right wall) with a
/// block on the floor, lit by a point light; camera, size and solver settings set in code.
fn scene() -> Scene {
    let mut s = Scene::empty();
    let v = DVec3::new;
    let grey = s.add_material(Material::diffuse("grey", 0.7));
    let red = s.add_material(Material {
        kd: v(0.7, 0.1, 0.1),
        ..Material::diffuse("red", 0.0)
    });
    let green = s.add_material(Material {
        kd: v(0.1, 0.6, 0.1),
        ..Material::diffuse("green", 0.0)
    });
    let (l, h) = (-1.0, 1.0);
    quad(
        &mut s,
        "floor",
        [v(l, 0., h), v(h, 0., h), v(h, 0., l), v(l, 0., l)],
        grey,
    );
    quad(
        &mut s,
        "back",
        [v(l, 0., l), v(h, 0., l), v(h, 2., l), v(l, 2., l)],
        grey,
    );
    quad(
        &mut s,
        "left",
        [v(l, 0., h), v(l, 0., l), v(l, 2., l), v(l, 2., h)],
        red,
    );
    quad(
        &mut s,
        "right",
        [v(h, 0., l), v(h, 0., h), v(h, 2., h), v(h, 2., l)],
        green,
    );
    // A block: five outward faces (its bottom rests on the floor).
    let (a, b) = (v(-0.3, 0.0, -0.4), v(0.3, 0.6, 0.2));
    let c = |x: f64, y: f64, z: f64| v(x, y, z);
    let faces = [
        [
            c(a.x, a.y, a.z),
            c(a.x, a.y, b.z),
            c(a.x, b.y, b.z),
            c(a.x, b.y, a.z),
        ],
        [
            c(b.x, a.y, a.z),
            c(b.x, b.y, a.z),
            c(b.x, b.y, b.z),
            c(b.x, a.y, b.z),
        ],
        [
            c(a.x, b.y, a.z),
            c(a.x, b.y, b.z),
            c(b.x, b.y, b.z),
            c(b.x, b.y, a.z),
        ],
        [
            c(a.x, a.y, a.z),
            c(a.x, b.y, a.z),
            c(b.x, b.y, a.z),
            c(b.x, a.y, a.z),
        ],
        [
            c(a.x, a.y, b.z),
            c(b.x, a.y, b.z),
            c(b.x, b.y, b.z),
            c(a.x, b.y, b.z),
        ],
    ];
    let first = s.meshes.len();
    for (i, f) in faces.into_iter().enumerate() {
        quad(&mut s, &format!("block{i}"), f, grey);
    }
    // The block is one object that moves (its links are made for that; the room does not move):
    // it slides 0.32 along x and turns 0.8 rad about its base over one second, the host's path.
    let block = s.add_object(first..s.meshes.len(), DMat4::IDENTITY, true);
    assert_eq!(block, BLOCK);
    let key = |time: f64, x: f64, turn: f64| ObjectKey {
        time,
        translate: Some(DVec3::new(x, 0.0, 0.0)),
        rotate: Some(DQuat::from_rotation_y(turn)),
    };
    s.set_object_keyframes(block, vec![key(0.0, 0.0, 0.0), key(1.0, 0.32, 0.8)])
        .expect("valid keys");
    s.lights.push(Light::Point {
        position: LIGHT,
        intensity: DVec3::splat(3.0),
    });
    s.environment = DVec3::splat(0.02);
    s.camera.eye = v(0.0, 1.0, 3.4);
    s.camera.fov_y_deg = 45.0;
    s.camera.target = v(0.0, 0.8, 0.0);
    s.camera.width = 128;
    s.camera.height = 128;
    s.solver.bins = 32;
    s.solver.element_size = 0.25;
    s
}

fn main() {
    if let Err(e) = run() {
        eprintln!("Error: {e}");
        std::process::exit(1);
    }
    let n = MESSAGES.load(Ordering::SeqCst);
    if n > 0 {
        eprintln!("Error: {n} Vulkan validation messages (above)");
        std::process::exit(1);
    }
}

fn run() -> Res<()> {
    let mut frames = 4usize;
    let (mut exr, mut png) = (None, None);
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--frames" => frames = args.next().ok_or("--frames needs a number")?.parse()?,
            "--exr" => {
                exr = Some(std::path::PathBuf::from(
                    args.next().ok_or("--exr needs a path")?,
                ))
            }
            "--png" => {
                png = Some(std::path::PathBuf::from(
                    args.next().ok_or("--png needs a path")?,
                ))
            }
            other => return Err(format!("unknown argument `{other}`").into()),
        }
    }
    let host = Host::new()?;
    // The host's allocator, for the host's own resources (here the readback buffer).
    let mut allocator = Allocator::new(&AllocatorCreateDesc {
        instance: host.instance.clone(),
        device: host.device.clone(),
        physical_device: host.physical_device,
        debug_settings: Default::default(),
        buffer_device_address: false,
        allocation_sizes: Default::default(),
    })?;
    let last = {
        // 1. Hand the device to the library and prepare the scene (links, plan, GPU
        //    resources, shadow maps, direct light).
        let ctx = Context::from_host(HostDevice {
            entry: host.entry.clone(),
            instance: host.instance.clone(),
            physical_device: host.physical_device,
            device: host.device.clone(),
            queue: host.queue,
            queue_family: host.family,
            rectangular_lines: host.rectangular_lines,
            wide_lines: host.wide_lines,
            debug_utils: true,
        })?;
        let scene = scene();
        let options = Options {
            context: Some(ctx),
            ..Default::default()
        };
        let mut engine = Engine::new(&scene, &options, &Silent)?;
        let (w, h) = (scene.camera.width, scene.camera.height);
        let bytes = w as u64 * h as u64 * 16; // the frame image is RGBA float32
        let d = &host.device;
        let buffer = unsafe {
            d.create_buffer(
                &vk::BufferCreateInfo::default()
                    .size(bytes)
                    .usage(vk::BufferUsageFlags::TRANSFER_DST),
                None,
            )?
        };
        let allocation = allocator.allocate(&AllocationCreateDesc {
            name: "host readback",
            requirements: unsafe { d.get_buffer_memory_requirements(buffer) },
            location: MemoryLocation::GpuToCpu,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        })?;
        unsafe { d.bind_buffer_memory(buffer, allocation.memory(), allocation.offset())? };
        let pool = unsafe {
            d.create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(host.family)
                    .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                None,
            )?
        };
        let cmd = unsafe {
            d.allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default()
                    .command_pool(pool)
                    .command_buffer_count(1),
            )?[0]
        };
        let fence = unsafe { d.create_fence(&vk::FenceCreateInfo::default(), None)? };
        let result = frames_loop(&host, &mut engine, cmd, fence, buffer, &allocation, frames);
        unsafe {
            d.device_wait_idle()?;
            d.destroy_fence(fence, None);
            d.destroy_command_pool(pool, None);
            d.destroy_buffer(buffer, None);
        }
        allocator.free(allocation)?;
        drop(engine); // the library's objects go before the device
        result?
    };
    drop(allocator);
    if let Some(p) = exr {
        last.write_exr(&p)?;
        eprintln!("wrote {}", p.display());
    }
    if let Some(p) = png {
        last.write_png(&p, 0.0)?;
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}

/// Per frame: move the block and the light, record iterations and the frame into the host's command buffer
/// with a copy of the result into the host's buffer, submit, wait, read. Returns the last image.
fn frames_loop(
    host: &Host,
    engine: &mut Engine,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    buffer: vk::Buffer,
    allocation: &Allocation,
    frames: usize,
) -> Res<Image> {
    let d = &host.device;
    let per_frame = engine.prepared().settings.iterations_per_frame;
    let mut image = None;
    for frame in 0..frames {
        let t = std::time::Instant::now();
        unsafe {
            d.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty())?;
            d.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default())?;
        }
        if frame == 0 {
            // 2a. The first frame starts from the initial state (emission, direct light).
            engine.begin_recording(cmd)?;
            engine.record_initialize(cmd)?;
        } else {
            // 2b. Later frames move the block along its keys (a quarter second per frame) and
            //     the light from the host's own data, and update: the next iterations continue
            //     from the previous frame's solution. The update follows the block in place:
            //     the moved link records and normals are uploaded by commands recorded into
            //     `cmd`; the shadow maps and direct light are done before it returns. Every
            //     third frame the host places the block off its keys instead
            //     (`set_object_transform`): the scene is prepared anew for that pose and the
            //     GPU objects are new, so begin (and read the frame's images) after the update.
            if frame % 3 == 2 {
                let off = DMat4::from_translation(DVec3::new(-0.1, 0.0, 0.05))
                    * DMat4::from_quat(DQuat::from_rotation_y(-0.3));
                engine.set_object_transform(BLOCK, off)?;
            } else {
                engine.set_time(0.25 * frame as f64)?;
            }
            engine.set_light(
                0,
                Light::Point {
                    position: LIGHT + DVec3::new(-0.1 * frame as f64, 0.0, -0.05 * frame as f64),
                    intensity: DVec3::splat(3.0),
                },
            )?;
            engine.record_update(cmd)?;
            engine.begin_recording(cmd)?;
        }
        // 3. Record `iterations_per_frame` iterations (4, the paper's), the frame, then the
        //    host's copy of the frame's output image.
        engine.record_iterations(cmd, per_frame)?;
        engine.record_draw(cmd)?;
        let out = engine.output_image()?;
        let (w, h) = (out.extent.width, out.extent.height);
        copy_to_buffer(d, cmd, &out, buffer);
        // 4. Submit on the host's queue and wait.
        unsafe {
            d.end_command_buffer(cmd)?;
            let cmds = [cmd];
            d.queue_submit(
                host.queue,
                &[vk::SubmitInfo::default().command_buffers(&cmds)],
                fence,
            )?;
            d.wait_for_fences(&[fence], true, u64::MAX)?;
            d.reset_fences(&[fence])?;
        }
        // 5. Read the result (linear RGB radiance) from the host's mapped buffer.
        let mapped = allocation
            .mapped_slice()
            .ok_or("readback buffer not mapped")?;
        let pixels: Vec<[f32; 3]> = mapped[..(w * h * 16) as usize]
            .chunks_exact(16)
            .map(|t| {
                let f = |i: usize| f32::from_le_bytes(t[4 * i..4 * i + 4].try_into().unwrap());
                [f(0), f(1), f(2)]
            })
            .collect();
        let img = Image {
            width: w,
            height: h,
            pixels,
        };
        if !img.is_finite() {
            return Err(format!("frame {frame}: non-finite pixels").into());
        }
        let mean = img.pixels.iter().flatten().map(|&v| v as f64).sum::<f64>()
            / (3 * img.pixels.len()) as f64;
        let timings = engine.recorded_timings()?;
        // Summed per pass over the frame's iterations, in first-seen order.
        let mut sums: Vec<(String, f64)> = Vec::new();
        for (name, ms) in timings {
            match sums.iter_mut().find(|s| s.0 == name) {
                Some(s) => s.1 += ms,
                None => sums.push((name, ms)),
            }
        }
        let passes: Vec<String> = sums.iter().map(|(n, ms)| format!("{n} {ms:.1}")).collect();
        let update = if frame == 0 {
            "none".to_string()
        } else {
            let f = engine.last_update().ok_or("no GPU backend")?;
            let ms = engine.update_times().total_ms;
            if engine.relinked() {
                format!("{ms:.0} ms, relinked and made anew")
            } else {
                format!(
                    "{ms:.0} ms, {}, {} bytes recorded, {}/{} shadow views drawn",
                    if f.in_place { "in place" } else { "made anew" },
                    f.uploaded_bytes,
                    f.shadow_views.0,
                    f.shadow_views.1
                )
            }
        };
        println!(
            "frame {frame}: mean radiance {mean:.4}, {:.0} ms (update: {update}); GPU ms: {}",
            t.elapsed().as_secs_f64() * 1e3,
            passes.join(", ")
        );
        image = Some(img);
    }
    image.ok_or_else(|| "no frames".into())
}

/// Records the copy of the engine's output image into `buffer`: the image from the state
/// `record_draw` leaves it in (`OutputImage`: layout, stages, access) to a transfer source and
/// back, so the engine's next draw finds it as it left it.
fn copy_to_buffer(d: &ash::Device, cmd: vk::CommandBuffer, out: &OutputImage, buffer: vk::Buffer) {
    let range = vk::ImageSubresourceRange::default()
        .aspect_mask(vk::ImageAspectFlags::COLOR)
        .level_count(1)
        .layer_count(1);
    // One transition of the output image: (stages, access, layout) before → after.
    type State = (vk::PipelineStageFlags2, vk::AccessFlags2, vk::ImageLayout);
    let transition = |from: State, to: State| {
        vk::ImageMemoryBarrier2::default()
            .src_stage_mask(from.0)
            .src_access_mask(from.1)
            .old_layout(from.2)
            .dst_stage_mask(to.0)
            .dst_access_mask(to.1)
            .new_layout(to.2)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(out.image)
            .subresource_range(range)
    };
    let drawn = (out.stages, out.access, out.layout);
    let copying = (
        vk::PipelineStageFlags2::COPY,
        vk::AccessFlags2::TRANSFER_READ,
        vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
    );
    let (to_copy, back) = (transition(drawn, copying), transition(copying, drawn));
    // The host reads the buffer after the fence: make the copy visible to it.
    let to_host = vk::MemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::COPY)
        .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::HOST)
        .dst_access_mask(vk::AccessFlags2::HOST_READ);
    unsafe {
        d.cmd_pipeline_barrier2(
            cmd,
            &vk::DependencyInfo::default().image_memory_barriers(std::slice::from_ref(&to_copy)),
        );
        let layers = vk::ImageSubresourceLayers::default()
            .aspect_mask(vk::ImageAspectFlags::COLOR)
            .layer_count(1);
        d.cmd_copy_image_to_buffer(
            cmd,
            out.image,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            buffer,
            &[vk::BufferImageCopy::default()
                .image_subresource(layers)
                .image_extent(vk::Extent3D {
                    width: out.extent.width,
                    height: out.extent.height,
                    depth: 1,
                })],
        );
        d.cmd_pipeline_barrier2(
            cmd,
            &vk::DependencyInfo::default()
                .image_memory_barriers(std::slice::from_ref(&back))
                .memory_barriers(std::slice::from_ref(&to_host)),
        );
    }
}
