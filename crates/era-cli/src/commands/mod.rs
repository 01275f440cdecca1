//! One file per verb: read the input, call the library, hand a typed result to
//! [`crate::output`]. The flags arrive as typed settings from [`crate::config`].

pub mod batch;
pub mod compare;
pub mod demo;
pub mod experiment;
pub mod files;
pub mod fleet;
pub mod frf;
pub mod friction;
pub mod identify;
pub mod oma;
pub mod plot;
pub mod refine;
pub mod simulate;
pub mod track;

/// What an identifying verb (`identify`, `oma`) hands back besides its files: the JSON
/// it prints with `--json` and the name of each output channel (the entries of a shape),
/// for `era batch`'s tables.
pub struct Done {
    /// The model JSON.
    pub json: serde_json::Value,
    /// One name per output channel: the file's channel name, else its 1-based number.
    pub channels: Vec<String>,
}
