//! Criterion benchmark of Rk45 (placeholder).
fn main() {}
