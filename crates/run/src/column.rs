//! Typed identities of output columns ([`Column`], [`Quantity`]): defined beside the models in
//! `flexprr-dynamics`, which produce their own tables, and re-exported here where the outputs
//! are assembled and written.

pub use flexprr_dynamics::{Column, Quantity};
