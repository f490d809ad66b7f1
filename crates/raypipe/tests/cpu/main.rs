//! The library's tests that need no GPU: the CPU reference against formulas written out here,
//! the BVHs against brute force, the model readers, the host structs against their WGSL twins
//! and the comparison harness itself. One binary, so that the tests link once.

#[path = "../common/mod.rs"]
mod common;

mod alpha;
mod bvh;
mod comparison;
mod environment;
mod filtering;
mod layers;
mod layout;
mod materials;
mod meshes;
mod path;
mod sampling;
mod tonemap;
mod watertight;
