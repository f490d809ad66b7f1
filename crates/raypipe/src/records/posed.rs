//! A moving scene's records posed at one time of its motion, and the tree over them rebuilt on the
//! CPU where the GPU does not build it: the half of a moving scene that both tracers share. The CPU
//! reference renders its records as they stand; [`crate::gpu::MovingScene`] puts it before a
//! renderer.

use crate::bvh::BuildTimings;
use crate::bvh::lbvh::{LbvhBuilder, depth_bound};
use crate::bvh::morton::MortonBits;
use crate::error::InputError;
use crate::modes::Accel;
use crate::records::PackedScene;
use crate::records::packed::MovedRecords;
use crate::scene::Scene;

/// The key width of every tree built as a scene moves, on the CPU as on the GPU: the same codes
/// give both the same tree.
pub(crate) const MOTION_BITS: MortonBits = MortonBits::Bits30;

/// Where a moving scene's primitives are posed and its tree built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PoseOn {
    /// Everything on the CPU: the records moved here, the tree built here (for the CPU reference,
    /// and for renderers that read uniform or texture memory, which no compute pass writes).
    Cpu,
    /// The tree is built on the GPU, and a glTF animation is skinned and morphed there too: the
    /// records here keep the loaded pose. Spheres that bounce are moved here, for the GPU to read.
    Gpu,
}

/// The times of the last two poses: what the scene shows, and what it showed before. The motion
/// is a function of time, so the two times give each surface's motion between frames.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Poses {
    /// `None` until the scene is first posed: it stands as loaded.
    pub current: Option<f32>,
    /// The pose before the current one; `None` until the scene is posed twice.
    pub previous: Option<f32>,
}

/// What one [`PosedScene::pose`] changed, and what it took on the CPU.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PoseStep {
    /// The records the motion rewrote here; `None` where nothing moved on the CPU.
    pub moved: Option<MovedRecords>,
    /// The motion evaluated and the moved records rewritten, in milliseconds.
    pub pose_ms: f64,
    /// The tree's build on the CPU, by phase, where it is built here and the walk reads one.
    pub build: Option<BuildTimings>,
}

/// A scene as loaded, its records at the last pose, and the CPU's tree builder where it builds.
pub struct PosedScene {
    /// As loaded: every pose is evaluated from it.
    scene: Scene,
    packed: PackedScene,
    /// Kept from build to build, so its buffers keep their capacity.
    builder: Option<LbvhBuilder<u64>>,
    /// Whether the walk reads the wide BVH, collapsed from each tree built.
    collapses: bool,
    /// Whether the records here move: not for an animation the GPU skins.
    moves_here: bool,
    poses: Poses,
}

impl PosedScene {
    /// `scene`'s records as loaded, for `accel`'s walk, posed and built where `on` says. Builds
    /// nothing yet: [`PosedScene::build`] or the first [`PosedScene::pose`] does.
    pub fn new(scene: &Scene, accel: Accel, on: PoseOn) -> Result<Self, InputError> {
        let animated_on_gpu = on == PoseOn::Gpu && scene.motion.as_ref().is_some_and(|m| m.is_animation());
        Ok(Self {
            scene: scene.clone(),
            packed: PackedScene::new(scene)?,
            builder: (on == PoseOn::Cpu && accel.uses_bvh()).then(LbvhBuilder::new),
            collapses: accel == Accel::Wide,
            moves_here: !animated_on_gpu,
            poses: Poses::default(),
        })
    }

    /// The scene as loaded.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The records as last posed here (as loaded, for an animation the GPU skins).
    pub fn packed(&self) -> &PackedScene {
        &self.packed
    }

    /// The path integrator's epoch of the records' samples (a frame's number: `Renderer::set_epoch`).
    pub fn set_epoch(&mut self, epoch: u32) {
        self.packed.path.globals.epoch = epoch;
    }

    /// The times of the last two poses.
    pub fn poses(&self) -> Poses {
        self.poses
    }

    /// A bound on the depth of every tree built as the scene moves: the walk's stack size.
    pub fn depth_bound(&self) -> u32 {
        depth_bound(self.packed.primitive_count(), MOTION_BITS)
    }

    /// Builds the tree over the records where they stand, where it is built here and the walk
    /// reads one.
    pub fn build(&mut self) -> Option<BuildTimings> {
        let builder = self.builder.as_mut()?;
        let mut timings = builder.build(&self.packed.primitive_boxes(), MOTION_BITS);
        self.packed.set_bvh(builder.to_bvh());
        if self.collapses {
            timings.collapse = self.packed.bvh.as_ref().map_or(0.0, |bvh| bvh.collapse());
        }
        Some(timings)
    }

    /// Poses the scene at `t` seconds of its motion: the records that move here rewritten, and the
    /// tree built again where it is built here. A still scene's tree is built again all the same
    /// (a benchmark of the rebuild poses one).
    pub fn pose(&mut self, t: f32) -> Result<PoseStep, InputError> {
        if !t.is_finite() {
            return Err(InputError::new(format!("time {t} is not finite")));
        }
        let start = web_time::Instant::now();
        let moved = match &self.scene.motion {
            Some(motion) if self.moves_here => Some(self.packed.apply(&motion.moved(&self.scene, t)?)),
            _ => None,
        };
        let pose_ms = start.elapsed().as_secs_f64() * 1e3;
        self.poses = Poses {
            current: Some(t),
            previous: self.poses.current,
        };
        Ok(PoseStep {
            moved,
            pose_ms,
            build: self.build(),
        })
    }
}
