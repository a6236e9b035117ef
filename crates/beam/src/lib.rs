//! beam layer of flexprr (placeholder).
