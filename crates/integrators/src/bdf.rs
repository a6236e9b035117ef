//! placeholder for bdf
