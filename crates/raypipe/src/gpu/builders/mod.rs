//! The GPU builders, each a set of compute passes: the LBVH (`lbvh`: Morton codes, radix sort,
//! bottom-up merges, refit), its threaded layout for the stack and threaded walks, its collapse
//! into compressed wide nodes, skinning and morphing (`deform`), and the driver's structures for
//! ray queries. `shared` is what they hand the tracer.

pub mod deform;
pub mod lbvh;
pub mod rayquery;
pub mod shared;
pub mod threaded_layout;
pub mod wide_collapse;
