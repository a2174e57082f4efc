//! Mouse-and-key camera of the viewer: orbit around the target or fly from the eye, keys move
//! both; the scene's camera is home. Changes are applied to the engine by the caller
//! (`Engine::set_camera`) only when something moved.

use antiradiance::scene::Camera;
use glam::{DQuat, DVec3};

/// What a mouse drag turns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// The eye circles the target.
    Orbit,
    /// The view direction turns about the eye.
    Fly,
}

/// Directions the keys move the camera in (view-relative, up is the scene's up).
#[derive(Clone, Copy, Debug)]
pub enum Move {
    /// W.
    Forward,
    /// S.
    Back,
    /// A.
    Left,
    /// D.
    Right,
    /// E.
    Up,
    /// Q.
    Down,
}

/// The interactive camera.
pub struct Control {
    home: Camera,
    /// The camera now.
    pub camera: Camera,
    /// What dragging does.
    pub mode: Mode,
    /// A key step: 2% of the scene's bounding-box diagonal.
    step: f64,
    /// Whether the camera changed since the engine last took it.
    pub changed: bool,
}

/// Radians per pixel of mouse drag.
const TURN: f64 = 0.005;

impl Control {
    /// Starts at `home`; `diagonal` is the scene's size (sets the key step).
    pub fn new(home: Camera, diagonal: f64) -> Self {
        Self {
            camera: home.clone(),
            home,
            mode: Mode::Orbit,
            step: (0.02 * diagonal).max(1e-6),
            changed: false,
        }
    }

    /// Back to the scene's camera.
    pub fn reset(&mut self) {
        self.camera = self.home.clone();
        self.changed = true;
    }

    /// Switches between orbit and fly.
    pub fn toggle_mode(&mut self) {
        self.mode = match self.mode {
            Mode::Orbit => Mode::Fly,
            Mode::Fly => Mode::Orbit,
        };
    }

    fn axes(&self) -> (DVec3, DVec3, DVec3) {
        let c = &self.camera;
        let forward = (c.target - c.eye).normalize();
        let right = forward.cross(c.up).normalize();
        (forward, right, c.up.normalize())
    }

    /// A drag by (`dx`, `dy`) pixels: orbit turns the eye about the target, fly the target
    /// about the eye; the view never reaches the up axis (it would have no right direction).
    pub fn drag(&mut self, dx: f64, dy: f64) {
        let (forward, right, up) = self.axes();
        let yaw = DQuat::from_axis_angle(up, -dx * TURN);
        let mut pitch = -dy * TURN;
        // Keep the view at least ~3° from the up axis.
        let elevation = forward.dot(up).clamp(-1.0, 1.0).asin();
        let limit = std::f64::consts::FRAC_PI_2 - 0.05;
        pitch = (elevation + pitch).clamp(-limit, limit) - elevation;
        let turn = yaw * DQuat::from_axis_angle(right, pitch);
        let c = &mut self.camera;
        match self.mode {
            Mode::Orbit => c.eye = c.target + turn * (c.eye - c.target),
            Mode::Fly => c.target = c.eye + turn * (c.target - c.eye),
        }
        self.changed = true;
    }

    /// Wheel by `lines`: orbit moves the eye toward the target (never onto it), fly moves
    /// eye and target forward.
    pub fn zoom(&mut self, lines: f64) {
        let c = &mut self.camera;
        match self.mode {
            Mode::Orbit => {
                let d = c.eye - c.target;
                let scaled = d * 0.9f64.powf(lines);
                if scaled.length() > 1e-3 * self.step {
                    c.eye = c.target + scaled;
                }
            }
            Mode::Fly => {
                let f = (c.target - c.eye).normalize() * self.step * lines;
                c.eye += f;
                c.target += f;
            }
        }
        self.changed = true;
    }

    /// A key step in `dir`: eye and target move together.
    pub fn step(&mut self, dir: Move) {
        let (forward, right, up) = self.axes();
        let v = match dir {
            Move::Forward => forward,
            Move::Back => -forward,
            Move::Left => -right,
            Move::Right => right,
            Move::Up => up,
            Move::Down => -up,
        } * self.step;
        self.camera.eye += v;
        self.camera.target += v;
        self.changed = true;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> Camera {
        Camera {
            eye: DVec3::new(0.0, 1.0, 4.0),
            target: DVec3::new(0.0, 1.0, 0.0),
            up: DVec3::Y,
            fov_y_deg: 40.0,
            width: 64,
            height: 64,
            supersample: 1,
            jitter: [0.0; 2],
            passes: 1,
            fov_axis: Default::default(),
        }
    }

    #[test]
    fn orbit_keeps_the_distance_and_fly_keeps_the_eye() {
        let mut c = Control::new(cam(), 3.0);
        c.drag(100.0, 40.0);
        let d = (c.camera.eye - c.camera.target).length();
        assert!((d - 4.0).abs() < 1e-12, "orbit distance {d}");
        assert_ne!(c.camera.eye, cam().eye);
        c.toggle_mode();
        let eye = c.camera.eye;
        c.drag(-50.0, 10.0);
        assert_eq!(c.camera.eye, eye);
        // Dragging far up stops short of the up axis.
        c.drag(0.0, -1e5);
        let f = (c.camera.target - c.camera.eye).normalize();
        assert!(f.dot(DVec3::Y).abs() < 0.9990, "{f:?}");
        c.reset();
        assert_eq!(c.camera, cam());
    }

    #[test]
    fn keys_move_eye_and_target_together() {
        let mut c = Control::new(cam(), 5.0);
        c.step(Move::Forward);
        c.step(Move::Right);
        let moved = c.camera.eye - cam().eye;
        assert!(
            (moved - DVec3::new(0.1, 0.0, -0.1)).length() < 1e-12,
            "{moved:?}"
        );
        assert_eq!(c.camera.target - c.camera.eye, cam().target - cam().eye);
    }
}
