//! scenarios layer of flexprr (placeholder).
