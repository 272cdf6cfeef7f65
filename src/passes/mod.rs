//! One module per kernel: its pipelines, bindings and `encode`.

pub mod baseline;
pub mod fill;
pub mod raster;
pub mod resolve;
