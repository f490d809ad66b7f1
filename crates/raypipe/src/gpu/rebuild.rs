//! The per-frame BVH rebuild on the GPU, the paper's answer to moving objects: the LBVH build in
//! compute passes and, for the stack and threaded walks, the threaded layout of its tree, recorded
//! into the same encoder as the frame so that no round trip to the host separates build and trace.
//!
//! A skinned or morphing glTF scene is posed before the build in the same encoder
//! ([`GpuDeform`]): the host writes a few matrices a frame, and no vertex crosses to the GPU.
//!
//! `render --frames`, `bench --rebuild` and a live viewer use it the same way:
//! [`SceneRebuild::move_to`] a time, [`SceneRebuild::encode`], then [`super::Renderer::encode`]
//! (or `read_frame_after`).

use super::build::{GpuLbvhBuilder, depth_bound};
use super::deform::GpuDeform;
use super::threaded::GpuThreadedLayout;
use super::upload::SharedBuffers;
use super::{GpuContext, GpuError};
use crate::bvh::BuildTimings;
use crate::bvh::morton::MortonBits;
use crate::error::InputError;
use crate::modes::Accel;
use crate::records::packed::MovedRecords;
use crate::records::{GpuSphere, PackedScene};
use crate::scene::Scene;

pub struct SceneRebuild {
    builder: GpuLbvhBuilder,
    /// For the walks that read the 16-byte depth-first nodes.
    layout: Option<GpuThreadedLayout>,
    /// Skinning and morphing, for a scene whose motion is glTF animation.
    deform: Option<GpuDeform>,
    /// Whether the walk reads a BVH: brute force moves the primitives but builds nothing.
    builds: bool,
}

impl SceneRebuild {
    /// Kernels and buffers for `packed`'s primitives, which are written here, and where `scene`
    /// moves by glTF animation, the skinning pass that poses them. They may move
    /// ([`SceneRebuild::move_to`]).
    pub async fn new(
        ctx: &GpuContext,
        scene: &Scene,
        packed: &PackedScene,
        accel: Accel,
        bits: MortonBits,
    ) -> Result<Self, GpuError> {
        let mut builder = GpuLbvhBuilder::new(ctx, bits, packed.spheres.len(), packed.triangles.len()).await?;
        builder.write_scene(packed).await?;
        let layout = match accel {
            Accel::Stack | Accel::Threaded => {
                Some(GpuThreadedLayout::new(ctx, &builder.buffers().nodes, packed.primitive_count()).await?)
            }
            Accel::Brute | Accel::Stackless => None,
        };
        let deform = match &scene.motion {
            Some(motion) => GpuDeform::new(ctx, motion, &builder.buffers().triangles, &packed.triangle_normals).await?,
            None => None,
        };
        Ok(Self {
            builder,
            layout,
            deform,
            builds: accel.uses_bvh(),
        })
    }

    /// Moves the primitives to `t` seconds of `scene`'s motion (`scene` as loaded) for the next
    /// [`SceneRebuild::encode`]. Skinning on the GPU needs only the frame's matrices; other motion
    /// moves `packed`'s records on the CPU and writes them here, and the records returned are those
    /// a renderer must rewrite ([`super::Renderer::write_moved`]).
    pub fn move_to(&self, scene: &Scene, packed: &mut PackedScene, t: f32) -> Result<Option<MovedRecords>, InputError> {
        if let Some(deform) = &self.deform {
            deform.write_pose(t)?;
            return Ok(None);
        }
        let Some(motion) = &scene.motion else {
            return Ok(None);
        };
        let moved = packed.apply(&motion.moved(scene, t)?);
        self.write_moved(packed, moved);
        Ok(Some(moved))
    }

    /// The skinning pass, where the scene has one.
    pub fn deform(&self) -> Option<&GpuDeform> {
        self.deform.as_ref()
    }

    /// New sphere positions for the next build (as many as the scene had).
    pub fn write_spheres(&self, spheres: &[GpuSphere]) {
        self.builder.write_spheres(spheres);
    }

    /// The primitives a motion moved in `scene`, for the next build and for the renderers that
    /// read them from here. (Moved triangles' normals live with the renderer:
    /// [`super::Renderer::write_records`].)
    pub fn write_moved(&self, scene: &PackedScene, moved: MovedRecords) {
        match moved {
            MovedRecords::Spheres => self.builder.write_spheres(&scene.spheres),
            MovedRecords::Triangles => self.builder.write_triangles(&scene.triangles),
        }
    }

    /// Records the skinning pass, where there is one, and the build (and the threaded layout) of
    /// the primitives as they will be when the encoder reaches it.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(deform) = &self.deform {
            deform.encode(encoder);
        }
        if !self.builds {
            return;
        }
        self.builder.encode(encoder, super::build::Codes::Computed);
        if let Some(layout) = &self.layout {
            layout.encode(encoder);
        }
    }

    /// Like [`SceneRebuild::encode`], refitting the last tree built instead of building anew:
    /// the skinning pass, the boxes recomputed bottom-up over the moved primitives, and the
    /// refitted boxes written into the threaded layout, whose order stands.
    pub fn encode_refit(&self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(deform) = &self.deform {
            deform.encode(encoder);
        }
        if !self.builds {
            return;
        }
        self.builder.encode_refit(encoder);
        if let Some(layout) = &self.layout {
            layout.encode_boxes(encoder);
        }
    }

    /// A bound on the depth of every tree this rebuild can make: the walk's stack size.
    pub fn depth_bound(&self) -> u32 {
        depth_bound(self.builder.count(), self.builder.bits())
    }

    /// What a renderer reads in place of the scene's own spheres and nodes.
    pub fn shared_buffers(&self) -> SharedBuffers {
        SharedBuffers {
            threaded_nodes: self.layout.as_ref().map(|l| l.threaded.clone()),
            bvh_frame: self.layout.as_ref().map(|l| l.frame.clone()),
            triangle_normals: self.deform.as_ref().map(|d| d.triangle_normals.clone()),
            ..self.builder.shared_buffers()
        }
    }

    pub fn builder(&self) -> &GpuLbvhBuilder {
        &self.builder
    }

    /// GPU time of the last skinning pass and of the last refit (with its threaded layout), where
    /// they ran and the adapter has timestamps.
    pub async fn read_skinning_ms(&self) -> Result<Option<f64>, GpuError> {
        match &self.deform {
            Some(deform) => deform.read_ms().await,
            None => Ok(None),
        }
    }

    pub async fn read_refit_ms(&self) -> Result<Option<f64>, GpuError> {
        let Some(refit) = self.builder.read_refit_ms().await? else {
            return Ok(None);
        };
        let layout = match &self.layout {
            Some(layout) => layout.read_ms(self.builder.context()).await?.unwrap_or(0.0),
            None => 0.0,
        };
        Ok(Some(refit + layout))
    }

    /// GPU time of each phase of the last rebuild submitted and finished (zeros without timestamp
    /// queries), the threaded layout's among them.
    pub async fn read_timings(&self) -> Result<BuildTimings, GpuError> {
        if !self.builds {
            return Ok(BuildTimings::default());
        }
        let mut timings = self.builder.read_timings().await?;
        if let Some(layout) = &self.layout {
            timings.layout = layout.read_ms(self.builder.context()).await?.unwrap_or(0.0);
        }
        Ok(timings)
    }
}
