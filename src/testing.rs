//! What the crate's own tests and benchmarks reach that is not API: kernels run outside a
//! frame, the hardware-raster baseline, and the embedded shader sources. Not covered by the
//! crate's semver.

pub use crate::gpu::shader_source;
pub use crate::passes::baseline::BaselinePass;
pub use crate::passes::raster::coverage_counts;
