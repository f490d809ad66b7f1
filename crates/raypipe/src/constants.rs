//! The numbers the two tracers agree on, the shader and the CPU reference alike: where a ray
//! ends, how far a secondary ray starts off its surface, what a miss writes, how samples step.
//! At the bottom of the library, as the scene and the frames use some of them too; the shaders
//! read them from the preamble that `records` writes.

/// Where a ray that hits nothing ends.
pub const T_FAR: f32 = 1e30;
/// A branch whose weight falls below this in every channel cannot change an 8-bit pixel; drop it.
pub const MIN_WEIGHT: f32 = 1e-3;
/// The depth channel's value where the primary ray hits nothing (the shader cannot write +inf).
pub const DEPTH_MISS: f32 = -1.0;
/// How far secondary rays start off the surface, along its normal.
pub const RAY_BIAS: f32 = 1e-4;
/// A ray closer to parallel with a plane than this misses it.
pub const PARALLEL_EPSILON: f32 = 1e-8;
/// Direction components smaller than this are replaced by it before inversion, so that the slab
/// test never computes 0 * inf.
pub const TINY_DIRECTION: f32 = 1e-20;
/// What an intersection returns for no hit.
pub const NO_HIT: f32 = -1.0;
/// The R2 sequence's steps per sample (Roberts 2018: 1/g and 1/g², g the plastic number) in 0.32
/// fixed point, so that sample positions are integer arithmetic: the same bits on every device.
pub const R2_STEP: [u32; 2] = [3_242_174_889, 2_447_445_414];

/// The most surfaces a ray passes through for blended triangles before the rest of its weight is
/// dropped: what keeps a pixel's work bounded whatever the scene.
pub(crate) const MAX_BLEND_LAYERS: u32 = 32;
/// Room on the ray stack for branches that wait while a ray goes on through blended surfaces,
/// beyond the one per level of depth.
pub(crate) const BLEND_STACK_ROOM: u32 = 8;

/// The tracer's ray stack (`RAY_STACK_SIZE`): depth-first with two branches keeps at most one
/// waiting sibling per level, plus the pair just pushed; where a ray goes on behind blended
/// surfaces, their branches wait too, in BLEND_STACK_ROOM more (a branch that finds the stack full
/// is dropped, alike on both tracers).
pub(crate) fn ray_stack_size(max_depth: u32, blend: bool) -> u32 {
    max_depth + 1 + if blend { BLEND_STACK_ROOM } else { 0 }
}

/// A footprint is its cone's width over the cosine between the ray and the surface, at least this:
/// at grazing angles the footprint is long, and reads the coarsest level.
pub(crate) const MIN_FOOTPRINT_COSINE: f32 = 1e-4;
