//! kinematics layer of flexprr (placeholder).
