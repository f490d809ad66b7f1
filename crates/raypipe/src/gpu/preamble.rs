//! The WGSL every GPU pipeline starts from, the builders' and the tracer's alike: the constants
//! shared with the CPU reference and the records shared with the host.

use crate::records::constants;

/// The records shared with the host.
pub(crate) const TYPES: &str = include_str!("shaders/types.wgsl");

/// What every shader module starts from: the constants shared with the CPU reference, and the
/// records shared with the host.
pub fn records_source() -> String {
    format!("{}\n{TYPES}", constants::wgsl())
}
