//! Criterion benchmark of Bdf (placeholder).
fn main() {}
