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

    /// Turns the eye about the target as a drag of `dx`, `dy` pixels does.
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        self.turn(-dx * ORBIT_PER_PIXEL, dy * ORBIT_PER_PIXEL);
    }

    /// Turns the eye about the target: `yaw` radians about the up axis, `pitch` about the right
    /// axis, short of looking straight along the up axis.
    pub fn turn(&mut self, yaw: f32, pitch: f32) {
        let c = &mut self.camera;
        let up = c.up.normalize();
        let offset = c.eye - c.target;
        let offset = Quat::from_axis_angle(up, yaw) * offset;
        let right = offset.cross(up).normalize_or_zero();
        let pitched = Quat::from_axis_angle(right, pitch) * offset;
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
        self.turn(degrees.to_radians(), 0.0);
    }

    /// Puts the eye on a sphere about the target, as model-viewer's `camera-orbit` does: `theta`
    /// radians about the up axis from the front (world +z where the up axis is +y), `phi` radians
    /// down from the up axis, at `distance` (`None`: as far as now).
    pub fn place(&mut self, theta: f32, phi: f32, distance: Option<f32>) {
        let c = &mut self.camera;
        let up = c.up.normalize();
        // The front: +z off the up axis; for a scene whose up is z, the current view's side.
        let front = (Vec3::Z - Vec3::Z.dot(up) * up)
            .try_normalize()
            .or_else(|| {
                let offset = c.eye - c.target;
                (offset - offset.dot(up) * up).try_normalize()
            })
            .unwrap_or_else(|| up.any_orthonormal_vector());
        let side = up.cross(front);
        // Short of the poles, where the view's basis would degenerate.
        let phi = phi.clamp(0.01, std::f32::consts::PI - 0.01);
        let distance = distance
            .unwrap_or_else(|| (c.eye - c.target).length())
            .max(MIN_DISTANCE);
        let direction = phi.cos() * up + phi.sin() * (theta.cos() * front + theta.sin() * side);
        c.eye = c.target + direction * distance;
    }

    /// The distance from the eye to the target in the scene's own camera.
    pub fn home_distance(&self) -> f32 {
        (self.home.eye - self.home.target).length()
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
    fn placing_the_eye_follows_model_viewers_orbit() {
        let mut control = CameraControl::new(Camera::default());
        let target = control.camera.target;
        let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
        control.place(0.0, std::f32::consts::FRAC_PI_2, Some(2.0));
        assert!(
            close(control.camera.eye, target + Vec3::new(0.0, 0.0, 2.0)),
            "front: +z"
        );
        control.place(std::f32::consts::FRAC_PI_2, std::f32::consts::FRAC_PI_2, None);
        assert!(
            close(control.camera.eye, target + Vec3::new(2.0, 0.0, 0.0)),
            "a quarter turn: +x"
        );
        control.place(0.0, std::f32::consts::FRAC_PI_4, Some(1.0));
        let half = std::f32::consts::FRAC_1_SQRT_2;
        assert!(
            close(control.camera.eye, target + Vec3::new(0.0, half, half)),
            "45 degrees from the up axis"
        );
    }

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
