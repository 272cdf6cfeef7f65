//! CPU references of the kernels, written to read like the WGSL (same names, same loop order,
//! same arithmetic order), so that a GPU/CPU mismatch points at one line.

pub mod ao;
pub mod blur;
pub mod composite;
pub mod direct;
pub mod dof;
pub mod frame;
pub mod mean;
pub mod motion_blur;
pub mod offscreen;
pub mod pyramid;
pub mod radiosity;
pub mod raster;
pub mod reflections;
pub mod resolve;
pub mod shadow;
pub mod slices;
pub mod spiral;
pub mod transparency;
pub mod upsample;
