//! The per-frame BVH rebuild on the GPU, the paper's answer to moving objects: the LBVH build in
//! compute passes and, for the stack and threaded walks, the threaded layout of its tree, recorded
//! into the same encoder as the frame so that no round trip to the host separates build and trace.
//!
//! `render --frames`, `bench --rebuild` and a live viewer use it the same way: write the moved
//! primitives, [`SceneRebuild::encode`], then [`super::Renderer::encode`] (or `read_frame_after`).

use super::build::{GpuLbvhBuilder, depth_bound};
use super::threaded::GpuThreadedLayout;
use super::upload::SharedBuffers;
use super::{GpuContext, GpuError};
use crate::bvh::BuildTimings;
use crate::bvh::morton::MortonBits;
use crate::modes::Accel;
use crate::records::packed::MovedRecords;
use crate::records::{GpuSphere, PackedScene};

pub struct SceneRebuild {
    builder: GpuLbvhBuilder,
    /// For the walks that read the 16-byte depth-first nodes.
    layout: Option<GpuThreadedLayout>,
}

impl SceneRebuild {
    /// Kernels and buffers for `scene`'s primitives, which are written here; they may move
    /// ([`SceneRebuild::write_moved`]).
    pub async fn new(ctx: &GpuContext, scene: &PackedScene, accel: Accel, bits: MortonBits) -> Result<Self, GpuError> {
        let mut builder = GpuLbvhBuilder::new(ctx, bits, scene.spheres.len(), scene.triangles.len()).await?;
        builder.write_scene(scene).await?;
        let layout = match accel {
            Accel::Stack | Accel::Threaded => {
                Some(GpuThreadedLayout::new(ctx, &builder.buffers().nodes, scene.primitive_count()).await?)
            }
            Accel::Brute | Accel::Stackless => None,
        };
        Ok(Self { builder, layout })
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

    /// Records the build (and the threaded layout) of the primitives as they will be when the
    /// encoder reaches it.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder) {
        self.builder.encode(encoder, super::build::Codes::Computed);
        if let Some(layout) = &self.layout {
            layout.encode(encoder);
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
            ..self.builder.shared_buffers()
        }
    }

    pub fn builder(&self) -> &GpuLbvhBuilder {
        &self.builder
    }

    /// GPU time of each phase of the last rebuild submitted and finished (zeros without timestamp
    /// queries); the threaded layout counts under `links`.
    pub async fn read_timings(&self) -> Result<BuildTimings, GpuError> {
        let mut timings = self.builder.read_timings().await?;
        if let Some(layout) = &self.layout {
            timings.links += layout.read_ms(self.builder.context()).await?.unwrap_or(0.0);
        }
        Ok(timings)
    }
}
