//! The viewer's animation and light controls: play/pause and scrub of the scene's keyframes,
//! and keys that move the selected analytic light. Every change goes through the engine's
//! scene updates (`Engine::set_time`, `Engine::set_light`, `Engine::update`); the frames after a
//! change continue from the previous solution with `iterations_per_frame` iterations each.

use antiradiance::engine::Engine;
use antiradiance::scene::Light;
use anyhow::Result;
use glam::{DQuat, DVec3};
use winit::keyboard::KeyCode;

/// Animation time, play state, the selected light and what changed since the last frame.
pub struct Playback {
    /// Scene time, seconds.
    pub time: f64,
    /// Seconds of scene time the keyframes span (0: nothing to play).
    duration: f64,
    /// Whether time advances.
    pub playing: bool,
    /// Seconds of scene time per frame when stepping (`--frames`); `None`: the wall clock.
    fixed_step: Option<f64>,
    /// The analytic light the keys move.
    selected: usize,
    /// Light moves: 2% of the scene's bounding-box diagonal per press.
    step: f64,
    /// Time or a light changed: the engine must update before the next frame.
    dirty: bool,
    /// Frames that still iterate after the last change (the scene's `iterations` worth).
    settle: usize,
    /// A light set since the last update (presses between two frames add up).
    pending: Option<(usize, Light)>,
}

/// Radians a directional light turns per key press.
const TURN: f64 = 5f64 * std::f64::consts::PI / 180.0;

impl Playback {
    /// For a scene whose keyframes span `duration` seconds (animated scenes start playing);
    /// `diagonal` is the scene's size, `fixed_step` the scene time per frame when not the clock.
    pub fn new(duration: f64, diagonal: f64, fixed_step: Option<f64>) -> Self {
        Self {
            time: 0.0,
            duration,
            playing: duration > 0.0,
            fixed_step,
            selected: 0,
            step: (0.02 * diagonal).max(1e-6),
            dirty: false,
            settle: 0,
            pending: None,
        }
    }

    /// Handles a key of the animation or light bindings; false when it is not one of them.
    pub fn key(&mut self, code: KeyCode, engine: &mut Engine) -> Result<bool> {
        let scrub = 0.05 * self.duration;
        match code {
            KeyCode::Space if self.duration > 0.0 => self.playing = !self.playing,
            KeyCode::ArrowLeft if self.duration > 0.0 => self.seek(self.time - scrub),
            KeyCode::ArrowRight if self.duration > 0.0 => self.seek(self.time + scrub),
            KeyCode::Home if self.duration > 0.0 => self.seek(0.0),
            KeyCode::Tab => {
                let n = engine.prepared().scene.lights.len();
                self.selected = if n == 0 { 0 } else { (self.selected + 1) % n };
            }
            KeyCode::KeyJ => self.move_light(engine, DVec3::NEG_X)?,
            KeyCode::KeyL => self.move_light(engine, DVec3::X)?,
            KeyCode::KeyI => self.move_light(engine, DVec3::NEG_Z)?,
            KeyCode::KeyK => self.move_light(engine, DVec3::Z)?,
            KeyCode::KeyU => self.move_light(engine, DVec3::NEG_Y)?,
            KeyCode::KeyO => self.move_light(engine, DVec3::Y)?,
            _ => return Ok(false),
        }
        Ok(true)
    }

    fn seek(&mut self, t: f64) {
        self.time = t.clamp(0.0, self.duration);
        self.dirty = true;
    }

    /// Moves the selected light along world axis `dir` (point and spot lights move; a
    /// directional light turns: J/L about the vertical, I/K/U/O about the horizontal).
    fn move_light(&mut self, engine: &mut Engine, dir: DVec3) -> Result<()> {
        if engine.method() != antiradiance::Method::Antiradiance {
            return Ok(()); // a baseline's solution does not follow moving lights
        }
        let pending = self.pending.take().filter(|p| p.0 == self.selected);
        let Some(light) = pending
            .map(|p| p.1)
            .or_else(|| engine.prepared().scene.lights.get(self.selected).cloned())
        else {
            return Ok(());
        };
        let moved = match light {
            Light::Point {
                position,
                intensity,
            } => Light::Point {
                position: position + dir * self.step,
                intensity,
            },
            Light::Spot {
                position,
                axis,
                intensity,
                cutoff,
                beam_width,
            } => Light::Spot {
                position: position + dir * self.step,
                axis,
                intensity,
                cutoff,
                beam_width,
            },
            Light::Directional {
                direction,
                irradiance,
            } => {
                let turn = if dir.x != 0.0 {
                    DQuat::from_rotation_y(dir.x * TURN)
                } else {
                    DQuat::from_rotation_x((dir.z + dir.y) * TURN)
                };
                Light::Directional {
                    direction: (turn * direction).normalize(),
                    irradiance,
                }
            }
            other @ Light::EmitterSample { .. } => other,
        };
        engine.set_light(self.selected, moved.clone())?;
        self.pending = Some((self.selected, moved));
        self.dirty = true;
        Ok(())
    }

    /// Before a frame: advances time when playing (`dt` wall seconds, or the fixed step),
    /// brings the engine up to date, and returns how many iterations the frame runs.
    pub fn advance(&mut self, engine: &mut Engine, dt: f64) -> Result<usize> {
        if self.playing {
            let dt = self.fixed_step.unwrap_or(dt);
            self.time = (self.time + dt) % self.duration;
            self.dirty = true;
        }
        let settings = &engine.prepared().settings;
        let (per_frame, iterations) = (settings.iterations_per_frame.max(1), settings.iterations);
        if self.dirty {
            engine.set_time(self.time)?;
            engine.update()?;
            self.dirty = false;
            self.pending = None;
            self.settle = iterations.div_ceil(per_frame).max(1);
        }
        Ok(if self.settle > 0 {
            self.settle -= 1;
            per_frame
        } else {
            0
        })
    }

    /// Whether frames must keep coming without input (playing, or still settling).
    pub fn busy(&self) -> bool {
        self.playing || self.settle > 0 || self.dirty
    }

    /// The title's part: time and play state, the selected light.
    pub fn status(&self, engine: &Engine) -> String {
        let mut parts = Vec::new();
        if self.duration > 0.0 {
            let state = if self.playing { "playing" } else { "paused" };
            parts.push(format!("t {:.2}/{:.2} s {state}", self.time, self.duration));
        }
        let lights = &engine.prepared().scene.lights;
        if let Some(l) = lights.get(self.selected) {
            parts.push(format!(
                "light {}/{} ({})",
                self.selected + 1,
                lights.len(),
                l.kind()
            ));
        }
        let update = engine.update_times().total_ms;
        if update > 0.0 {
            let relinked = if engine.relinked() { ", relinked" } else { "" };
            parts.push(format!("update {update:.0} ms{relinked}"));
        }
        parts.join(" · ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use antiradiance::engine::Options;
    use antiradiance::progress::Silent;
    use antiradiance::scene::{Material, Scene};
    use antiradiance::BackendKind;

    /// A floor under a point light, on the CPU backend (no device needed).
    fn engine() -> Engine {
        let mut s = Scene::empty();
        let m = s.add_material(Material::diffuse("grey", 0.5));
        let v = DVec3::new;
        let floor = vec![
            v(-1., 0., 1.),
            v(1., 0., 1.),
            v(1., 0., -1.),
            v(-1., 0., -1.),
        ];
        s.add_mesh("floor", floor, vec![[0, 1, 2], [0, 2, 3]], m);
        s.lights.push(Light::Point {
            position: v(0.0, 1.0, 0.0),
            intensity: DVec3::ONE,
        });
        s.camera.width = 8;
        s.camera.height = 8;
        s.solver.bins = 32;
        s.solver.element_size = 0.5;
        s.solver.iterations = 8;
        s.solver.iterations_per_frame = 4;
        let options = Options {
            backend: BackendKind::Cpu,
            ..Default::default()
        };
        Engine::new(&s, &options, &Silent).unwrap()
    }

    #[test]
    fn light_keys_move_the_light_and_the_next_frames_iterate() {
        let mut e = engine();
        // The floor's diagonal is 2√2: a step is 2% of it.
        let mut p = Playback::new(0.0, 8f64.sqrt(), None);
        assert!(!p.playing, "nothing to play without keyframes");
        assert!(!p.key(KeyCode::Space, &mut e).unwrap());
        assert!(p.key(KeyCode::KeyL, &mut e).unwrap());
        assert!(p.key(KeyCode::KeyL, &mut e).unwrap());
        assert!(p.key(KeyCode::KeyO, &mut e).unwrap());
        assert_eq!(p.advance(&mut e, 0.0).unwrap(), 4, "iterations_per_frame");
        let Light::Point { position, .. } = e.prepared().scene.lights[0] else {
            panic!("not a point light");
        };
        let step = 0.02 * 8f64.sqrt();
        let want = DVec3::new(2.0 * step, 1.0 + step, 0.0);
        assert!((position - want).length() < 1e-12, "{position:?}");
        assert!(!e.relinked(), "a light move keeps the links");
        // The scene's 8 iterations at 4 per frame: one more frame iterates, then none.
        assert_eq!(p.advance(&mut e, 0.0).unwrap(), 4);
        assert_eq!(p.advance(&mut e, 0.0).unwrap(), 0);
        assert!(!p.busy());
    }
}
