//! The modes every layer shares: how a ray finds its closest primitive, and how the scene's records
//! reach the shader. They sit at the bottom of the module graph, so that the CPU tracer, the GPU
//! renderer and their callers name the same types.

use crate::choice::impl_choice;

/// How a ray finds its closest primitive. The default is the threaded walk; on the software
/// adapters measured so far the stack walk is faster (docs/BENCHMARKS.md), and the default stays
/// until a real GPU has been measured (a software rasterizer measures algorithms, not GPUs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Accel {
    /// Every ray against every primitive.
    Brute,
    /// The linear BVH, walked with a per-pixel stack, nearer child first.
    Stack,
    /// The linear BVH, walked without a stack (Hapala et al. 2011): parent links, nearer child first.
    Stackless,
    /// The linear BVH, walked without a stack along escape links, in fixed depth-first order.
    #[default]
    Threaded,
    /// The linear BVH collapsed into compressed 8-wide nodes (Ylitie et al. 2017), walked with a
    /// stack of node groups, children in the order of the ray's octant.
    Wide,
    /// The driver's own acceleration structures (a BLAS of triangles, one of spheres as boxes, a
    /// TLAS over them) walked by ray queries: ray-tracing hardware where the GPU has it. Vulkan,
    /// DX12 and Metal adapters with ray queries only.
    RayQuery,
}

impl_choice!(
    Accel,
    [
        (Brute, "brute", "every ray against every primitive"),
        (
            Stack,
            "stack",
            "the linear BVH, walked with a per-pixel stack, nearer child first"
        ),
        (
            Stackless,
            "stackless",
            "the linear BVH, walked without a stack (Hapala et al. 2011): parent links, nearer child first"
        ),
        (
            Threaded,
            "threaded",
            "the linear BVH, walked without a stack along escape links, in fixed depth-first order"
        ),
        (
            Wide,
            "wide",
            "the linear BVH collapsed into compressed 8-wide nodes (Ylitie et al. 2017), children in the order of the ray's octant"
        ),
        (
            RayQuery,
            "rayquery",
            "the driver's acceleration structures, walked by ray queries (adapters with ray queries only)"
        ),
    ]
);

impl Accel {
    /// Whether it walks raypipe's own BVH, which the host or the GPU builds for it.
    pub fn uses_bvh(self) -> bool {
        Accel::BVH.contains(&self)
    }

    /// Whether it needs the adapter's ray queries (`wgpu::Features::EXPERIMENTAL_RAY_QUERY`).
    pub fn needs_ray_queries(self) -> bool {
        self == Accel::RayQuery
    }

    /// The walks over the BVH, without brute force.
    pub const BVH: [Accel; 4] = [Accel::Stack, Accel::Stackless, Accel::Threaded, Accel::Wide];
}

/// How light is carried from a hit to the eye.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Integrator {
    /// The paper's: direct light with hard shadows from the lights, an ambient term, and the
    /// branches of mirrors and glass (a glossy reflection drawn per sample), to a fixed depth.
    #[default]
    Whitted,
    /// Unidirectional path tracing: a BSDF sample per bounce, the lights and the environment
    /// sampled at every vertex and weighted by multiple importance sampling, Russian roulette; no
    /// ambient term.
    Path,
}

impl_choice!(
    Integrator,
    [
        (
            Whitted,
            "whitted",
            "the paper's: direct light, hard shadows, an ambient term, mirrors and glass"
        ),
        (
            Path,
            "path",
            "path tracing: light, environment and emitters sampled at every bounce, weighted by MIS"
        ),
    ]
);

/// The order the driver's bottom-level structures hold their primitives in, with
/// [`Accel::RayQuery`]: a driver whose builder keeps the order it is given (lavapipe's) builds its
/// tree from it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BlasOrder {
    /// Morton order of the centroids: neighbours in space are neighbours in the list.
    #[default]
    Morton,
    /// The scene's own order (a file's): what the sort buys, measured.
    Scene,
}

impl_choice!(
    BlasOrder,
    [
        (Morton, "morton", "Morton order of the centroids"),
        (Scene, "scene", "the scene's own order (a file's)"),
    ]
);

/// How the BVH over a scene's primitives is built on the host.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Builder {
    /// The linear BVH (Karras 2012), built in parallel in milliseconds: the paper's tree, and the
    /// one a moving scene gets again every frame.
    #[default]
    Lbvh,
    /// Top-down binned SAH, serial and about 50 times slower to build, for a tree that costs some
    /// 10 % fewer tests a ray (docs/BENCHMARKS.md): for still scenes, whose tree is built once.
    Sah,
}

impl_choice!(
    Builder,
    [
        (
            Lbvh,
            "lbvh",
            "the linear BVH (Karras 2012), built in parallel: the paper's tree, rebuilt every frame where the scene moves"
        ),
        (
            Sah,
            "sah",
            "top-down binned SAH, serial: a better tree for a still scene, built once"
        ),
    ]
);

impl Builder {
    /// Whether this builder's tree can follow a scene that moves: such a tree is rebuilt every
    /// frame, which is the LBVH's job; the others build a still scene's tree once.
    pub fn follows_motion(self) -> bool {
        self == Builder::Lbvh
    }
}

/// How scene records reach the fragment shader.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum MemoryMode {
    /// Uniform buffers: fast, but small (64 KiB per array on most adapters).
    Uniform,
    /// Storage buffers: up to the adapter's buffer limit.
    #[default]
    Storage,
    /// Textures read with textureLoad (rgba32float; rgba32uint for the BVH's nodes): the route
    /// where fragment shaders have no storage buffers (WebGL2).
    Texture,
}

impl_choice!(
    MemoryMode,
    [
        (
            Uniform,
            "uniform",
            "uniform buffers: fast, but small (64 KiB per array on most adapters)"
        ),
        (Storage, "storage", "storage buffers: up to the adapter's buffer limit"),
        (
            Texture,
            "texture",
            "textures read with textureLoad (rgba32float; rgba32uint for the BVH's nodes): the route where fragment shaders have no storage buffers (WebGL2)"
        ),
    ]
);

/// Which shader stage runs the tracer. Both call the same tracer functions and write the same
/// targets, bit for bit alike on one adapter; WebGL2 has the fragment stage only.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Pipeline {
    /// The paper's route: a full-screen triangle, the tracer in the fragment stage.
    #[default]
    Fragment,
    /// A compute dispatch of 8x8 workgroups over the image, writing storage textures.
    Compute,
}

impl_choice!(
    Pipeline,
    [
        (
            Fragment,
            "fragment",
            "the graphics pipeline: a full-screen triangle, the tracer in the fragment stage"
        ),
        (
            Compute,
            "compute",
            "a compute dispatch of 8x8 workgroups over the image, writing storage textures"
        ),
    ]
);

/// What a render shows or writes of a frame: the `--aov` of `render`, the view of the window and
/// the page. All but `Cost` come from one trace; `Cost` traces with the cost count instead of rays.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Aov {
    /// Shaded colour: sRGB in PNG files and on screen, linear in EXR files.
    #[default]
    Color,
    /// Distance from the eye to the first hit (+inf where nothing is hit): channel `Z` of a float
    /// EXR; on screen, white near the eye fading to black.
    Depth,
    /// First-hit shading normals, mapped from [-1, 1] to [0, 1].
    Normal,
    /// Each primary ray's cost (BVH nodes tested: box tests of internal nodes, primitive tests of
    /// leaves; primitives tested for brute force) as a heat map with a legend. PNG only.
    Cost,
}

impl_choice!(
    Aov,
    [
        (Color, "color", "shaded colour"),
        (Depth, "depth", "distance to the first hit"),
        (Normal, "normal", "first-hit normals"),
        (Cost, "cost", "BVH nodes each primary ray tested, as a heat map"),
    ]
);

impl Aov {
    /// What the trace counts in a pixel's fourth channel for this view.
    pub fn count(self) -> Count {
        match self {
            Aov::Cost => Count::Cost,
            Aov::Color | Aov::Depth | Aov::Normal => Count::Rays,
        }
    }
}

/// What a pixel's fourth colour channel holds ([`Aov::count`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Count {
    /// The rays traced for the pixel (primary, shadow, secondary).
    #[default]
    Rays,
    /// The cost of its primary ray (BVH nodes tested; spheres tested for brute force), as the shader's cost variant.
    Cost,
}

/// A backend a caller can ask for; without one, `WGPU_BACKEND` or wgpu's default order decides.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    /// Vulkan (lavapipe here).
    Vulkan,
    /// OpenGL or GLES (llvmpipe through EGL here).
    Gl,
    /// Metal (Apple).
    Metal,
    /// Direct3D 12 (Windows).
    Dx12,
}

impl_choice!(
    Backend,
    [
        (Vulkan, "vulkan", "Vulkan"),
        (Gl, "gl", "OpenGL or OpenGL ES, through EGL (WebGL2 in a browser)"),
        (Metal, "metal", "Metal"),
        (Dx12, "dx12", "Direct3D 12"),
    ]
);

impl Backend {
    /// wgpu's flag for the backend.
    pub fn backends(self) -> wgpu::Backends {
        match self {
            Backend::Vulkan => wgpu::Backends::VULKAN,
            Backend::Gl => wgpu::Backends::GL,
            Backend::Metal => wgpu::Backends::METAL,
            Backend::Dx12 => wgpu::Backends::DX12,
        }
    }
}
