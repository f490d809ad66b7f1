//! The GPU builders, each a set of compute passes: the LBVH (`lbvh`: Morton codes, radix sort,
//! bottom-up merges, refit), its threaded layout for the stack and threaded walks, its collapse
//! into compressed wide nodes, skinning and morphing (`deform`), and the driver's structures for
//! ray queries. `shared` is what they hand the tracer.

#[cfg(feature = "internals")]
pub mod deform;
#[cfg(not(feature = "internals"))]
pub(crate) mod deform;
pub mod lbvh;
pub mod rayquery;
pub mod shared;
#[cfg(feature = "internals")]
pub mod threaded_layout;
#[cfg(not(feature = "internals"))]
pub(crate) mod threaded_layout;
pub mod wide_collapse;
