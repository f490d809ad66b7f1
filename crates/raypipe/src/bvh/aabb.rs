//! Axis-aligned bounding boxes.

use glam::Vec3;

/// An axis-aligned box; empty when `min` exceeds `max` on an axis ([`Aabb::EMPTY`] grows into any
/// point).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// The low corner.
    pub min: Vec3,
    /// The high corner.
    pub max: Vec3,
}

impl Aabb {
    /// The box that contains nothing: the identity of `union`.
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// The box from `min` to `max`.
    pub fn new(min: Vec3, max: Vec3) -> Self {
        Self { min, max }
    }

    /// The box around a sphere.
    pub fn around_sphere(center: Vec3, radius: f32) -> Self {
        Self::new(center - Vec3::splat(radius), center + Vec3::splat(radius))
    }

    /// Exact: min and max never round, so unions agree bit for bit on every device in any order.
    pub fn union(self, other: Aabb) -> Aabb {
        Aabb::new(self.min.min(other.min), self.max.max(other.max))
    }

    /// The box grown to take in `point`.
    pub fn grow(self, point: Vec3) -> Aabb {
        Aabb::new(self.min.min(point), self.max.max(point))
    }

    /// The smallest box holding every point; [`Aabb::EMPTY`] for none.
    pub fn around_points(points: impl IntoIterator<Item = Vec3>) -> Aabb {
        points.into_iter().fold(Aabb::EMPTY, Aabb::grow)
    }

    /// The box's centre.
    pub fn centroid(self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Whether the box holds no point (min above max on some axis).
    pub fn is_empty(self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// The box's surface area, the SAH's measure; 0 for an empty box.
    pub fn surface_area(self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.max - self.min;
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// Whether `other` lies inside this box (faces included).
    pub fn contains(self, other: Aabb) -> bool {
        self.min.cmple(other.min).all() && self.max.cmpge(other.max).all()
    }
}
