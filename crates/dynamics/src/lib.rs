//! dynamics layer of flexprr (placeholder).
