//! Criterion benchmark of Abm (placeholder).
fn main() {}
