//! `antiradiance view`: a window on the engine (GPU backend) through winit and ash-window. The
//! viewer is an embedding host like any other: it makes its own instance (with the window
//! system's surface extensions) and device (with a swapchain), hands them to the library
//! (`Context::from_host`), solves as `render` does, and per frame updates what moved
//! (`playback`), records the engine's iterations and draw into its own command buffer, then a
//! blit of the frame image onto the swapchain image.

mod camera;
pub mod command;
mod playback;
mod swapchain;
mod vulkan;

use antiradiance::engine::{Engine, Options};
use antiradiance::frame::image::write_atomic;
use antiradiance::gpu::{Context, HostDevice};
use antiradiance::Scene;
use anyhow::{anyhow, bail, Context as _, Result};
use ash::vk;
use camera::{Control, Move};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;
use swapchain::{record_present, Readback, Source, Swapchain};
use vulkan::Host;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::window::{Window, WindowId};

/// What `view` was asked to do.
pub struct ViewRequest {
    /// The scene.
    pub scene: Scene,
    /// Engine options (GPU backend; the context is the viewer's).
    pub options: Options,
    /// Run this many frames, then exit.
    pub frames: Option<u32>,
    /// After the last of `frames`, save the presented image here (PNG).
    pub screenshot: Option<PathBuf>,
    /// After the first frame, ask for this window size.
    pub resize: Option<(u32, u32)>,
    /// Scene seconds per frame while playing with `frames` (the wall clock otherwise).
    pub step: f64,
    /// Exposure in stops at the start (`-` and `=` change it by half a stop).
    pub exposure: f64,
}

/// Opens the window and runs until it is closed (or `frames` were presented).
pub fn run(req: ViewRequest) -> Result<()> {
    let event_loop = EventLoop::new().context(
        "cannot open a window (no display: set DISPLAY, or run under xvfb-run from scripts/setup.sh)",
    )?;
    event_loop.set_control_flow(if req.frames.is_some() {
        ControlFlow::Poll
    } else {
        ControlFlow::Wait
    });
    let mut app = App {
        req,
        viewer: None,
        error: None,
    };
    event_loop.run_app(&mut app)?;
    // Everything on the device is gone before validation is judged.
    drop(app.viewer.take());
    if let Some(e) = app.error {
        return Err(e);
    }
    let n = vulkan::VALIDATION_MESSAGES.load(std::sync::atomic::Ordering::SeqCst);
    if n > 0 {
        bail!("{n} Vulkan validation messages (above)");
    }
    Ok(())
}

struct App {
    req: ViewRequest,
    viewer: Option<Viewer>,
    error: Option<anyhow::Error>,
}

impl App {
    fn fail(&mut self, el: &ActiveEventLoop, e: anyhow::Error) {
        self.error.get_or_insert(e);
        el.exit();
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.viewer.is_none() {
            match Viewer::new(el, &self.req) {
                Ok(v) => {
                    v.window.request_redraw();
                    self.viewer = Some(v);
                }
                Err(e) => self.fail(el, e),
            }
        }
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(v) = self.viewer.as_mut() else {
            return;
        };
        match event {
            WindowEvent::CloseRequested => el.exit(),
            WindowEvent::Resized(_) => {
                v.stale = true;
                v.window.request_redraw();
            }
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                let PhysicalKey::Code(code) = event.physical_key else {
                    return;
                };
                let Some(engine) = v.engine.as_mut() else {
                    return;
                };
                match v.playback.key(code, engine) {
                    Ok(true) => return v.window.request_redraw(),
                    Ok(false) => {}
                    Err(e) => return self.fail(el, e),
                }
                let c = &mut v.control;
                match code {
                    KeyCode::Minus | KeyCode::NumpadSubtract => v.exposure -= 0.5,
                    KeyCode::Equal | KeyCode::NumpadAdd => v.exposure += 0.5,
                    KeyCode::Escape => el.exit(),
                    KeyCode::KeyW => c.step(Move::Forward),
                    KeyCode::KeyS => c.step(Move::Back),
                    KeyCode::KeyA => c.step(Move::Left),
                    KeyCode::KeyD => c.step(Move::Right),
                    KeyCode::KeyE => c.step(Move::Up),
                    KeyCode::KeyQ => c.step(Move::Down),
                    KeyCode::KeyF => c.toggle_mode(),
                    KeyCode::KeyR => c.reset(),
                    _ => return,
                }
                v.window.request_redraw();
            }
            WindowEvent::MouseInput {
                state,
                button: MouseButton::Left,
                ..
            } => v.dragging = state == ElementState::Pressed,
            WindowEvent::CursorMoved { position, .. } => {
                let (x, y) = (position.x, position.y);
                if let (true, Some((px, py))) = (v.dragging, v.cursor) {
                    v.control.drag(x - px, y - py);
                    v.window.request_redraw();
                }
                v.cursor = Some((x, y));
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y as f64,
                    MouseScrollDelta::PixelDelta(p) => p.y / 40.0,
                };
                v.control.zoom(lines);
                v.window.request_redraw();
            }
            WindowEvent::RedrawRequested => {
                let done = match v.frame(self.req.frames, self.req.screenshot.as_deref()) {
                    Ok(done) => done,
                    Err(e) => return self.fail(el, e),
                };
                if let (1, Some((w, h))) = (v.presented, self.req.resize) {
                    // Applied now or by a later Resized event; `frame` checks the size too.
                    let _ = v.window.request_inner_size(PhysicalSize::new(w, h));
                }
                if done {
                    el.exit();
                } else if self.req.frames.is_some() || v.playback.busy() {
                    v.window.request_redraw();
                }
            }
            _ => {}
        }
    }
}

/// The window, the viewer's device, the engine on it and the per-frame objects. Dropped in
/// dependency order: the engine and the library's context, then the frame objects and the
/// swapchain, then the device and the instance (`host`), then the window.
struct Viewer {
    engine: Option<Engine>,
    ctx: Option<Arc<Context>>,
    pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    image_available: vk::Semaphore,
    swap: Option<Swapchain>,
    /// The swapchain must be recreated before the next frame (resize, out-of-date, suboptimal).
    stale: bool,
    control: Control,
    playback: playback::Playback,
    dragging: bool,
    cursor: Option<(f64, f64)>,
    presented: u32,
    last: Option<Instant>,
    /// Smoothed seconds per frame.
    frame_s: f64,
    /// When the first frame was presented (the `--frames` summary's rate starts there).
    first: Option<Instant>,
    /// Exposure in stops (the frame's output times 2^exposure before the sRGB blit).
    exposure: f64,
    linear_blit: bool,
    host: Host,
    window: Window,
}

impl Viewer {
    fn new(el: &ActiveEventLoop, req: &ViewRequest) -> Result<Self> {
        let progress = crate::cli::progress::Bars::default();
        let cam = antiradiance::engine::Options {
            context: None,
            ..req.options.clone()
        }
        .resolve(&req.scene)?
        .camera;
        let window = el.create_window(
            Window::default_attributes()
                .with_title("antiradiance")
                .with_inner_size(PhysicalSize::new(cam.width, cam.height)),
        )?;
        let host = Host::new(
            window.display_handle()?.as_raw(),
            window.window_handle()?.as_raw(),
            vulkan::validation_requested(),
            req.options.device.as_deref(),
        )?;
        let ctx = Context::from_host(HostDevice {
            entry: host.inst.entry.clone(),
            instance: host.inst.instance.clone(),
            physical_device: host.physical_device,
            device: host.device.clone(),
            queue: host.queue,
            queue_family: host.queue_family,
            rectangular_lines: host.rectangular_lines,
            wide_lines: host.wide_lines,
            debug_utils: host.inst.debug_utils,
        })?;
        let diagonal = {
            let (lo, hi) = req.scene.bounds();
            (hi - lo).length()
        };
        let d = host.device.clone();
        let pool = unsafe {
            d.create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(host.queue_family)
                    .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                None,
            )
        }?;
        let mut v = Self {
            engine: None,
            ctx: Some(ctx.clone()),
            pool,
            cmd: vk::CommandBuffer::null(),
            fence: vk::Fence::null(),
            image_available: vk::Semaphore::null(),
            swap: None,
            stale: true,
            control: Control::new(cam.clone(), diagonal),
            playback: playback::Playback::new(
                req.scene.duration(),
                diagonal,
                req.frames.map(|_| req.step),
            ),
            dragging: false,
            cursor: None,
            presented: 0,
            last: None,
            frame_s: 0.0,
            first: None,
            exposure: req.exposure,
            linear_blit: false,
            host,
            window,
        };
        v.cmd = unsafe {
            d.allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default()
                    .command_pool(pool)
                    .command_buffer_count(1),
            )
        }?[0];
        v.fence = unsafe { d.create_fence(&vk::FenceCreateInfo::default(), None) }?;
        v.image_available =
            unsafe { d.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }?;
        let props = unsafe {
            v.host.inst.instance.get_physical_device_format_properties(
                v.host.physical_device,
                vk::Format::R32G32B32A32_SFLOAT,
            )
        };
        let f = props.optimal_tiling_features;
        if !f.contains(vk::FormatFeatureFlags::BLIT_SRC) {
            bail!("the device cannot blit from the frame's float32 image (BLIT_SRC)");
        }
        v.linear_blit = f.contains(vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR);
        let options = Options {
            context: Some(ctx),
            ..req.options.clone()
        };
        // Solve once as `render` does (the scene's iterations, the monitor's fallbacks).
        let mut engine = Engine::new(&req.scene, &options, &progress)?;
        let stats = engine.render(&progress)?.stats;
        eprintln!(
            "{} elements, {} links, {} bins, {} iterations on {}",
            stats.elements, stats.links, stats.bins, stats.iterations, stats.device
        );
        v.engine = Some(engine);
        Ok(v)
    }

    fn engine(&mut self) -> Result<&mut Engine> {
        self.engine.as_mut().ok_or_else(|| anyhow!("no engine"))
    }

    /// Draws and presents one frame; true when `frames` have been presented (the screenshot,
    /// if asked for, is then written).
    fn frame(&mut self, frames: Option<u32>, shot: Option<&std::path::Path>) -> Result<bool> {
        let size = self.window.inner_size();
        if size.width == 0 || size.height == 0 {
            return Ok(false); // minimized: nothing to present to
        }
        let resized = self
            .swap
            .as_ref()
            .is_some_and(|s| (s.extent.width, s.extent.height) != (size.width, size.height));
        if self.stale || resized || self.swap.is_none() {
            let old = self.swap.take();
            self.swap = Some(Swapchain::new(&self.host, (size.width, size.height), old)?);
            self.stale = false;
        }
        let swap = self.swap.as_ref().expect("made above");
        let (swap_raw, images, extent, format) =
            (swap.raw, swap.images.clone(), swap.extent, swap.format);
        let render_finished = swap.render_finished.clone();
        let (d, sfn) = (self.host.device.clone(), self.host.swapchain_fn.clone());
        let acquired = unsafe {
            sfn.acquire_next_image(swap_raw, u64::MAX, self.image_available, vk::Fence::null())
        };
        let (index, suboptimal) = match acquired {
            Ok(r) => r,
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
                self.stale = true;
                self.window.request_redraw();
                return Ok(false);
            }
            Err(e) => return Err(e).context("acquiring a swapchain image"),
        };
        // An image is ours: update what moved (time, lights; the engine keeps the camera),
        // then take the camera.
        let dt = self.last.map_or(0.0, |t| t.elapsed().as_secs_f64());
        let engine = self.engine.as_mut().ok_or_else(|| anyhow!("no engine"))?;
        let iterations = self.playback.advance(engine, dt)?;
        if self.control.changed {
            let camera = self.control.camera.clone();
            self.engine()?.set_camera(camera)?;
            self.control.changed = false;
        }
        let last = frames.is_some_and(|n| self.presented + 1 >= n);
        let readback = match (last, shot) {
            (true, Some(_)) => Some(Readback::new(
                &self.host,
                extent.width as u64 * extent.height as u64 * 4,
            )?),
            _ => None,
        };
        let (image, finished) = (images[index as usize], render_finished[index as usize]);
        let cmd = self.cmd;
        let linear = self.linear_blit;
        let result = (|| -> Result<()> {
            unsafe {
                d.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty())?;
                d.begin_command_buffer(
                    cmd,
                    &vk::CommandBufferBeginInfo::default()
                        .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                )?;
            }
            let exposure = 2f32.powf(self.exposure as f32);
            let engine = self.engine()?;
            // Set every frame: an update that makes the frame anew starts it at 1.
            engine.set_exposure(exposure)?;
            engine.begin_recording(cmd)?;
            // Warm-started iterations after a change (`iterations_per_frame`), then the frame.
            engine.record_iterations(cmd, iterations)?;
            engine.record_draw(cmd)?;
            let out = engine.output_image()?;
            let src = Source {
                image: out.image,
                extent: out.extent,
                linear,
            };
            record_present(&d, cmd, &src, image, extent, readback.as_ref());
            unsafe {
                d.end_command_buffer(cmd)?;
                let waits = [vk::SemaphoreSubmitInfo::default()
                    .semaphore(self.image_available)
                    .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
                let signals = [vk::SemaphoreSubmitInfo::default()
                    .semaphore(finished)
                    .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
                let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
                d.queue_submit2(
                    self.host.queue,
                    &[vk::SubmitInfo2::default()
                        .wait_semaphore_infos(&waits)
                        .command_buffer_infos(&cmds)
                        .signal_semaphore_infos(&signals)],
                    self.fence,
                )?;
            }
            Ok(())
        })();
        if let Err(e) = result {
            if let Some(r) = &readback {
                r.destroy(&self.host);
            }
            return Err(e);
        }
        let (swaps, indices, waits) = ([swap_raw], [index], [finished]);
        let presented = unsafe {
            sfn.queue_present(
                self.host.queue,
                &vk::PresentInfoKHR::default()
                    .wait_semaphores(&waits)
                    .swapchains(&swaps)
                    .image_indices(&indices),
            )
        };
        unsafe {
            d.wait_for_fences(&[self.fence], true, u64::MAX)?;
            d.reset_fences(&[self.fence])?;
        }
        match presented {
            Ok(false) if !suboptimal => {}
            Ok(_) | Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => self.stale = true,
            Err(e) => return Err(e).context("presenting"),
        }
        self.presented += 1;
        let passes = self.title()?;
        let first = *self.first.get_or_insert_with(Instant::now);
        if last && self.presented > 1 {
            let s = first.elapsed().as_secs_f64() / (self.presented - 1) as f64;
            eprintln!(
                "presented {} frames of {}×{}: {:.1} fps after the first ({:.1} ms per frame; last frame's GPU ms: {passes})",
                self.presented,
                extent.width,
                extent.height,
                1.0 / s,
                s * 1e3
            );
        }
        if let (Some(r), Some(path)) = (&readback, shot) {
            let bytes = r.read(&self.host);
            r.destroy(&self.host);
            let rgb = swapchain::to_rgb(&bytes?, format);
            write_atomic(path, |w| {
                image::write_buffer_with_format(
                    w,
                    &rgb,
                    extent.width,
                    extent.height,
                    image::ColorType::Rgb8,
                    image::ImageFormat::Png,
                )
                .map_err(std::io::Error::other)
            })?;
            eprintln!(
                "wrote {} ({}×{}, frame {})",
                path.display(),
                extent.width,
                extent.height,
                self.presented
            );
        }
        Ok(last)
    }

    /// Frame rate and the frame's GPU pass times in the title; returns the pass times.
    fn title(&mut self) -> Result<String> {
        let now = Instant::now();
        if let Some(t) = self.last.replace(now) {
            let dt = (now - t).as_secs_f64();
            self.frame_s = if self.frame_s == 0.0 {
                dt
            } else {
                0.9 * self.frame_s + 0.1 * dt
            };
        }
        let mode = self.control.mode;
        let exposure = self.exposure;
        let engine = self.engine.as_mut().ok_or_else(|| anyhow!("no engine"))?;
        let status = self.playback.status(engine);
        let timings = engine.recorded_timings()?;
        // Summed per pass over the frame's iterations, in first-seen order.
        let mut sums: Vec<(String, f64)> = Vec::new();
        for (name, ms) in timings {
            match sums.iter_mut().find(|s| s.0 == name) {
                Some(s) => s.1 += ms,
                None => sums.push((name, ms)),
            }
        }
        let passes: Vec<String> = sums
            .iter()
            .map(|(name, ms)| format!("{name} {ms:.1}"))
            .collect();
        let rate = if self.frame_s > 0.0 {
            format!("{:.1} fps", 1.0 / self.frame_s)
        } else {
            "– fps".into()
        };
        let passes = passes.join(", ");
        let sep = if status.is_empty() { "" } else { " · " };
        self.window.set_title(&format!(
            "antiradiance · {rate} · GPU ms: {passes} · {mode:?} · exposure {exposure:+.1}{sep}{status}"
        ));
        Ok(passes)
    }
}

impl Drop for Viewer {
    fn drop(&mut self) {
        let d = self.host.device.clone();
        unsafe {
            let _ = d.device_wait_idle();
        }
        self.engine.take();
        self.ctx.take();
        if let Some(mut s) = self.swap.take() {
            s.destroy(&self.host);
        }
        unsafe {
            d.destroy_semaphore(self.image_available, None);
            d.destroy_fence(self.fence, None);
            d.destroy_command_pool(self.pool, None);
        }
    }
}
