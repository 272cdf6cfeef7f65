//! One module per kernel: its pipelines, bindings and `encode`.

pub mod ao;
pub mod baseline;
pub mod blur;
pub mod composite;
pub mod direct;
pub mod fill;
pub mod present;
pub mod pyramid;
pub mod radiosity;
pub mod raster;
pub mod reflections;
pub mod resolve;
pub mod shadow;
