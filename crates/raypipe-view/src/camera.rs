//! The viewer's camera: orbit around the target, pan, dolly and fly. It stays the scene's own camera,
//! to the bit, until the user moves it, so that a still first frame is `raypipe render`'s image.

use glam::{Quat, Vec3};
use raypipe::scene::Camera;

/// Radians of orbit per pixel dragged.
const ORBIT_PER_PIXEL: f32 = 0.008;
/// Closest the eye may come to the target, as a fraction of the starting distance.
const MIN_DISTANCE: f32 = 1e-3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraControl {
    /// Where `R` returns to: the scene's camera.
    pub home: Camera,
    pub camera: Camera,
}

impl CameraControl {
    pub fn new(home: Camera) -> Self {
        Self { home, camera: home }
    }

    pub fn reset(&mut self) {
        self.camera = self.home;
    }

    fn distance(&self) -> f32 {
        (self.camera.eye - self.camera.target).length()
    }

    /// Turns the eye about the target: `dx` pixels about the up axis, `dy` about the right axis,
    /// short of looking straight along the up axis.
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        let c = &mut self.camera;
        let up = c.up.normalize();
        let offset = c.eye - c.target;
        let yaw = Quat::from_axis_angle(up, -dx * ORBIT_PER_PIXEL);
        let offset = yaw * offset;
        let right = offset.cross(up).normalize_or_zero();
        let pitched = Quat::from_axis_angle(right, dy * ORBIT_PER_PIXEL) * offset;
        // Stay a little off the pole, where the view's basis would degenerate.
        let cos = pitched.normalize().dot(up).abs();
        let offset = if cos < 0.995 && right != Vec3::ZERO {
            pitched
        } else {
            offset
        };
        c.eye = c.target + offset;
    }

    /// Turns the camera about the target by `degrees` about its up axis (the scripted `--orbit`).
    pub fn orbit_degrees(&mut self, degrees: f32) {
        self.orbit(-degrees.to_radians() / ORBIT_PER_PIXEL, 0.0);
    }

    /// Moves eye and target together across the view by `dx`, `dy` pixels of a `height`-pixel view.
    pub fn pan(&mut self, dx: f32, dy: f32, height: f32) {
        let (_, right, up) = self.basis();
        let per_pixel = 2.0 * self.distance() * (self.camera.fov_degrees.to_radians() * 0.5).tan() / height;
        let shift = (-dx * right + dy * up) * per_pixel;
        self.camera.eye += shift;
        self.camera.target += shift;
    }

    /// Moves the eye towards the target (positive `steps`) or away from it, by a tenth a step.
    pub fn dolly(&mut self, steps: f32) {
        let c = &mut self.camera;
        let offset = c.eye - c.target;
        let scale = 0.9f32.powf(steps).max(MIN_DISTANCE);
        c.eye = c.target + offset * scale;
    }

    /// Flies eye and target along the view: `forward`, `right` and `up` in units of the distance to
    /// the target.
    pub fn fly(&mut self, forward: f32, right: f32, up: f32) {
        let (f, r, u) = self.basis();
        let shift = (forward * f + right * r + up * u) * self.distance();
        self.camera.eye += shift;
        self.camera.target += shift;
    }

    /// The view's forward, right and up, as `GpuCamera` derives them.
    fn basis(&self) -> (Vec3, Vec3, Vec3) {
        let c = &self.camera;
        let forward = (c.target - c.eye).normalize();
        let right = forward.cross(c.up).normalize();
        (forward, right, right.cross(forward))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_full_orbit_returns_and_the_distance_stays() {
        let mut control = CameraControl::new(Camera::default());
        let distance = control.distance();
        for _ in 0..36 {
            control.orbit_degrees(10.0);
            assert!((control.distance() - distance).abs() < 1e-4 * distance);
        }
        assert!((control.camera.eye - control.home.eye).length() < 1e-3 * distance);
        assert_ne!(
            {
                control.orbit(40.0, 0.0);
                control.camera
            },
            control.home
        );
        control.reset();
        assert_eq!(control.camera, control.home);
    }

    #[test]
    fn orbiting_up_stops_short_of_the_pole() {
        let mut control = CameraControl::new(Camera::default());
        for _ in 0..1000 {
            control.orbit(0.0, 50.0);
        }
        let c = control.camera;
        let cos = (c.eye - c.target).normalize().dot(c.up.normalize()).abs();
        assert!(cos < 0.996, "{cos}");
    }

    #[test]
    fn dolly_and_pan_move_as_asked() {
        let mut control = CameraControl::new(Camera::default());
        let distance = control.distance();
        control.dolly(1.0);
        assert!((control.distance() - 0.9 * distance).abs() < 1e-5);
        let target = control.camera.target;
        control.pan(10.0, 0.0, 100.0);
        assert!(control.camera.target != target);
        assert!((control.distance() - 0.9 * distance).abs() < 1e-4);
    }
}
