//! The per-frame BVH rebuild on the GPU, the paper's answer to moving objects: the LBVH build in
//! compute passes and, for the stack and threaded walks, the threaded layout of its tree, recorded
//! into the same encoder as the frame so that no round trip to the host separates build and trace.
//!
//! A skinned or morphing glTF scene is posed before the build in the same encoder
//! ([`GpuDeform`]): the host writes a few matrices a frame, and no vertex crosses to the GPU.
//!
//! [`crate::gpu::MovingScene`] drives it for a moving scene; benchmarks and tests of the build
//! reach it directly.

use crate::bvh::BuildTimings;
use crate::bvh::lbvh::depth_bound;
use crate::bvh::morton::MortonBits;
use crate::gpu::builders::deform::GpuDeform;
use crate::gpu::builders::lbvh::{Codes, GpuLbvhBuilder};
use crate::gpu::builders::shared::SharedBuffers;
use crate::gpu::builders::threaded_layout::GpuThreadedLayout;
use crate::gpu::builders::wide_collapse::GpuWideCollapse;
use crate::gpu::trace::renderer::{Renderer, RendererOptions};
use crate::gpu::{GpuContext, GpuError};
use crate::modes::Accel;
use crate::records::PackedScene;
use crate::records::packed::MovedRecords;
use crate::scene::Scene;

/// A scene's primitives in the GPU build's buffers, and the passes that rebuild (or refit) their
/// tree there before a frame: skinning, the LBVH, its threaded layout or wide collapse.
pub struct SceneRebuild {
    builder: GpuLbvhBuilder,
    /// For the walks that read the 16-byte depth-first nodes.
    layout: Option<GpuThreadedLayout>,
    /// For the wide walk: the collapse into compressed 8-wide nodes.
    wide: Option<GpuWideCollapse>,
    /// Skinning and morphing, for a scene whose motion is glTF animation.
    deform: Option<GpuDeform>,
    /// Whether the walk reads a BVH: brute force moves the primitives but builds nothing.
    builds: bool,
}

impl SceneRebuild {
    /// Kernels and buffers for `packed`'s primitives, which are written here, and where `scene`
    /// moves by glTF animation, the skinning pass that poses them ([`GpuDeform::write_pose`]).
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
            Accel::Brute | Accel::Stackless | Accel::Wide | Accel::RayQuery => None,
        };
        let wide = match accel {
            Accel::Wide => {
                let depth = depth_bound(builder.count(), builder.bits());
                let nodes = &builder.buffers().nodes;
                Some(GpuWideCollapse::new(ctx, nodes, packed.primitive_count(), depth).await?)
            }
            _ => None,
        };
        let deform = match &scene.motion {
            Some(motion) => GpuDeform::new(ctx, motion, &builder.buffers().triangles, &packed.triangle_normals).await?,
            None => None,
        };
        Ok(Self {
            builder,
            layout,
            wide,
            deform,
            builds: accel.uses_bvh(),
        })
    }

    /// The skinning pass, where the scene has one.
    pub fn deform(&self) -> Option<&GpuDeform> {
        self.deform.as_ref()
    }

    /// New sphere positions for the next build (as many as the scene had).
    #[cfg(feature = "internals")]
    pub fn write_spheres(&self, spheres: &[crate::records::GpuSphere]) {
        self.builder.write_spheres(spheres);
    }

    /// The primitives a motion moved in `scene`, for the next build and for the renderers that
    /// read them from here. (Moved triangles' normals live with the renderer:
    /// [`crate::gpu::Renderer::write_records`].)
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
        self.builder.encode(encoder, Codes::Computed);
        if let Some(layout) = &self.layout {
            layout.encode(encoder);
        }
        if let Some(wide) = &self.wide {
            wide.encode(encoder);
        }
    }

    /// Like [`SceneRebuild::encode`], refitting the last tree built instead of building anew:
    /// the skinning pass, the boxes recomputed bottom-up over the moved primitives, and the
    /// refitted boxes written into the threaded layout, whose order stands. The wide nodes are
    /// collapsed anew: which children a node opens follows their boxes.
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
        if let Some(wide) = &self.wide {
            wide.encode(encoder);
        }
    }

    /// A bound on the depth of every tree this rebuild can make: the walk's stack size.
    pub fn depth_bound(&self) -> u32 {
        depth_bound(self.builder.count(), self.builder.bits())
    }

    /// A renderer of `scene` (the packing this rebuild was made for) that traces what this rebuild
    /// writes: record [`SceneRebuild::encode`] before [`Renderer::encode`] in the same encoder.
    /// Storage memory only.
    pub async fn renderer(
        &self,
        ctx: &GpuContext,
        scene: &PackedScene,
        options: RendererOptions,
    ) -> Result<Renderer, GpuError> {
        Renderer::with_shared_buffers(ctx, scene, &self.shared_buffers(), self.depth_bound(), options).await
    }

    /// What a renderer reads in place of the scene's own spheres and nodes.
    pub fn shared_buffers(&self) -> SharedBuffers {
        SharedBuffers {
            threaded_nodes: self.layout.as_ref().map(|l| l.threaded.clone()),
            bvh_frame: self.layout.as_ref().map(|l| l.frame.clone()),
            wide: self.wide.as_ref().map(|w| w.texels.clone()),
            triangle_normals: self.deform.as_ref().map(|d| d.triangle_normals.clone()),
            ..self.builder.shared_buffers()
        }
    }

    /// The LBVH build, whose buffers hold the primitives and the tree.
    #[cfg(feature = "internals")]
    pub fn builder(&self) -> &GpuLbvhBuilder {
        &self.builder
    }

    /// The wide collapse, with the wide walk.
    #[cfg(feature = "internals")]
    pub fn wide(&self) -> Option<&GpuWideCollapse> {
        self.wide.as_ref()
    }

    /// GPU time of the last skinning pass, where it ran and the adapter has timestamps.
    pub async fn read_skinning_ms(&self) -> Result<Option<f64>, GpuError> {
        match &self.deform {
            Some(deform) => deform.read_ms().await,
            None => Ok(None),
        }
    }

    /// GPU time of the last refit (with its threaded layout or wide collapse), where it ran and
    /// the adapter has timestamps.
    pub async fn read_refit_ms(&self) -> Result<Option<f64>, GpuError> {
        let Some(refit) = self.builder.read_refit_ms().await? else {
            return Ok(None);
        };
        let layout = match &self.layout {
            Some(layout) => layout.read_ms(self.builder.context()).await?.unwrap_or(0.0),
            None => 0.0,
        };
        let collapse = match &self.wide {
            Some(wide) => wide.read_ms(self.builder.context()).await?.unwrap_or(0.0),
            None => 0.0,
        };
        Ok(Some(refit + layout + collapse))
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
        if let Some(wide) = &self.wide {
            timings.collapse = wide.read_ms(self.builder.context()).await?.unwrap_or(0.0);
        }
        Ok(timings)
    }
}
