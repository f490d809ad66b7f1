//! How a scene moves as time passes: the one description that `render --frames`, `bench`, the
//! window and the page all play. A moving scene keeps its primitives as loaded; [`Motion::moved`]
//! says where the ones that move are at a time, so that a tracer rewrites only those records.

use super::animation::{Animated, MovedTriangles};
use super::{Scene, within_reach};
use crate::error::{Element, InputError};
use glam::Vec3;
use std::sync::Arc;

/// How a scene moves.
#[derive(Clone, Debug, PartialEq)]
pub enum Motion {
    /// Every sphere flies straight on and bounces off the walls of a box (`bounce:N`).
    Bounce(Bounce),
    /// glTF clips moving triangles: node animation, skinning, morph targets. One per animated
    /// file the scene places.
    Animations(Vec<Arc<Animated>>),
}

/// Spheres that fly at constant velocities and bounce off the walls of a box.
#[derive(Clone, Debug, PartialEq)]
pub struct Bounce {
    /// One per sphere, in units per second.
    pub velocities: Vec<Vec3>,
    /// The box the spheres' centres stay in.
    pub lo: Vec3,
    /// See `lo`.
    pub hi: Vec3,
}

/// Where the moving primitives are at one time.
#[derive(Clone, Debug, PartialEq)]
pub enum Moved {
    /// Every sphere's centre.
    Spheres(Vec<Vec3>),
    /// Runs of triangles with their new corners.
    Triangles(Vec<MovedTriangles>),
}

impl Motion {
    /// Seconds after which nothing changes: the longest clip; `None` for motion without end.
    pub fn duration(&self) -> Option<f32> {
        match self {
            Motion::Bounce(_) => None,
            Motion::Animations(animations) => Some(animations.iter().map(|a| a.duration()).fold(0.0, f32::max)),
        }
    }

    /// Whether the motion is glTF animation, whose meshes a GPU can pose itself from each frame's
    /// joint matrices and morph weights (the spheres of `bounce` are moved by the host).
    pub fn is_animation(&self) -> bool {
        matches!(self, Motion::Animations(_))
    }

    /// `t` wrapped into the motion's duration, for a scene that plays in a loop (unchanged for
    /// motion without end).
    pub fn looped(&self, t: f32) -> f32 {
        match self.duration() {
            Some(duration) if duration > 0.0 => t.rem_euclid(duration),
            _ => t,
        }
    }

    /// Where `scene`'s moving primitives are at time `t` seconds (`scene` as loaded: at time 0).
    /// Fails where the pose leaves the space the tracers can reach.
    pub fn moved(&self, scene: &Scene, t: f32) -> Result<Moved, InputError> {
        if !t.is_finite() {
            return Err(InputError::new(format!("time {t} is not finite")));
        }
        match self {
            Motion::Bounce(bounce) => Ok(Moved::Spheres(bounce.centers(scene, t))),
            Motion::Animations(animations) => {
                let moved: Vec<MovedTriangles> = animations.iter().flat_map(|a| a.moved(t)).collect();
                for run in &moved {
                    for (k, corners) in run.vertices.iter().enumerate() {
                        if !corners.iter().all(|&v| v.is_finite() && within_reach(v)) {
                            return Err(InputError::of(
                                Element::Triangle(run.first + k),
                                format!("at {t} s the animation moves it out of reach (or to NaN)"),
                            ));
                        }
                    }
                }
                Ok(Moved::Triangles(moved))
            }
        }
    }
}

impl Bounce {
    /// The spheres' centres at time `t`: on a triangle wave, reflected at each wall.
    fn centers(&self, scene: &Scene, t: f32) -> Vec<Vec3> {
        let span = self.hi - self.lo;
        scene
            .spheres
            .iter()
            .zip(&self.velocities)
            .map(|(sphere, v)| {
                let travelled = (sphere.center - self.lo + *v * t).rem_euclid(2.0 * span);
                let folded = Vec3::select(travelled.cmpgt(span), 2.0 * span - travelled, travelled);
                self.lo + folded
            })
            .collect()
    }
}

impl Moved {
    /// Moves `scene`'s primitives here.
    pub fn apply(&self, scene: &mut Scene) {
        match self {
            Moved::Spheres(centers) => {
                for (sphere, &center) in scene.spheres.iter_mut().zip(centers) {
                    sphere.center = center;
                }
            }
            Moved::Triangles(runs) => {
                for run in runs {
                    let triangles = &mut scene.triangles[run.first..run.first + run.vertices.len()];
                    for (k, triangle) in triangles.iter_mut().enumerate() {
                        triangle.vertices = run.vertices[k];
                        if let Some(normals) = &run.normals {
                            triangle.normals = Some(normals[k]);
                        }
                    }
                }
            }
        }
    }
}

impl Scene {
    /// The scene at `t` seconds of its motion (itself, for a still scene).
    pub fn at_time(&self, t: f32) -> Result<Scene, InputError> {
        let mut scene = self.clone();
        if let Some(motion) = &self.motion {
            motion.moved(self, t)?.apply(&mut scene);
        }
        Ok(scene)
    }
}
