//! The one error type of the crate.

use std::path::PathBuf;

/// Everything that can go wrong with a user's input or device.
///
/// Every variant names its cause in one line (`Display`), so the command line can print it as is.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// A scene file is malformed; `location` names the accessor, line or element.
    #[error("{path}: {location}: {message}")]
    SceneFormat {
        /// The file.
        path: PathBuf,
        /// Where in the file (line, accessor, mesh, material).
        location: String,
        /// What is wrong.
        message: String,
    },
    /// A scene's contents are invalid (index out of range, NaN position, empty scene...).
    #[error("invalid scene: {0}")]
    InvalidScene(String),
    /// A setting is out of its valid range.
    #[error("invalid setting `{name}`: {message}")]
    InvalidSetting {
        /// The setting's name.
        name: &'static str,
        /// Why it is invalid.
        message: String,
    },
    /// A built-in scene name that does not exist.
    #[error("unknown built-in scene `{0}` (known: {known})", known = crate::scene::builtin::NAMES.join(", "))]
    UnknownBuiltin(String),
    /// No GPU adapter could be found.
    #[error("no GPU adapter found: {0}")]
    NoAdapter(String),
    /// The device lacks a feature the requested path needs.
    #[error("the device lacks the feature {0}")]
    MissingFeature(&'static str),
    /// A size or count is beyond what the device allows.
    #[error("{what} needs {needed} {unit} but the device allows at most {limit} {unit}")]
    ExceedsLimit {
        /// What is too big.
        what: String,
        /// What it needs.
        needed: u64,
        /// The device limit.
        limit: u64,
        /// What `needed` and `limit` count (`bytes`, `storage buffers`).
        unit: &'static str,
    },
    /// A G-buffer layer the last frame did not draw was asked for.
    #[error(
        "layer {layer} was not drawn (the last frame drew {drawn} layer(s); the plan draws layer 1 only for an effect that reads it)"
    )]
    LayerNotDrawn {
        /// The layer asked for.
        layer: usize,
        /// Layers the last frame drew (0 before the first frame).
        drawn: usize,
    },
    /// An imported buffer does not match its declared size or usage.
    #[error("imported buffer `{name}`: {message}")]
    ImportedBuffer {
        /// Which buffer.
        name: &'static str,
        /// What is wrong.
        message: String,
    },
    /// Requesting the device failed.
    #[error("could not open the GPU device: {0}")]
    RequestDevice(String),
    /// The GPU reported an error (validation or out of memory) while running a pass.
    #[error("GPU error in {label}: {message}")]
    Gpu {
        /// The pass.
        label: String,
        /// The driver's message.
        message: String,
    },
    /// Reading a buffer back from the GPU failed.
    #[error("reading back `{0}` from the GPU failed")]
    Readback(String),
    /// An input image (an environment map) could not be read or is unusable.
    #[error("{path}: {message}")]
    ImageRead {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// Encoding an output image failed.
    #[error("{path}: could not write image: {message}")]
    ImageWrite {
        /// The file.
        path: PathBuf,
        /// The encoder's message.
        message: String,
    },
}

/// The crate's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io { path: path.into(), source }
    }
    pub(crate) fn format(
        path: impl Into<PathBuf>,
        location: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Error::SceneFormat { path: path.into(), location: location.into(), message: message.into() }
    }
    pub(crate) fn setting(name: &'static str, message: impl Into<String>) -> Self {
        Error::InvalidSetting { name, message: message.into() }
    }
}
