//! The machine viewer of flexprr: a self-contained HTML page and static SVG figures of a
//! flexible-link 3-PRR run.
//!
//! - [`ViewerData`]: the plain data drawn (guides with travel limits, platform joints,
//!   per-frame slider positions and platform pose, per-link mode shapes, modal coordinates,
//!   axial forces, first-mode frequencies and buckling intervals, and the coupled model's
//!   platform deviation). Checked by [`ViewerData::validate`].
//! - [`viewer_html`] / [`viewer_html_with`]: one HTML file with data, styles and script
//!   inline (no network, no server). The series are decimated ([`ViewerOptions`]): uniform
//!   frame strides for the animation, min/max buckets for the plots so no extreme is lost,
//!   and packed as base64 `f32`.
//! - [`machine_svg`] and [`snapshots_svg`]: the machine with its reachable workspace,
//!   type-II singularity locus and path; the deformed links at a few instants.
//!
//! ```
//! use flexprr_viewer::{GuideView, LinkView, ViewerData, viewer_html};
//!
//! // A still frame of a toy machine: three guides, links of 0.2 m, one sine mode.
//! let guide = |angle: f64| {
//!     let (s, c) = angle.to_radians().sin_cos();
//!     GuideView { anchor: [-0.25 * c, -0.25 * s], direction: [c, s], travel: (-0.2, 0.2) }
//! };
//! let xi: Vec<f64> = (0..=10).map(|j| j as f64 / 10.0).collect();
//! let link = LinkView {
//!     length: 0.2,
//!     basis: "sine".into(),
//!     mode_shapes: vec![xi.iter().map(|x| (std::f64::consts::PI * x).sin()).collect()],
//!     xi,
//!     modal: vec![vec![1e-4]],
//!     axial_force: vec![-12.0],
//!     first_frequency: vec![110.0],
//!     buckling: vec![],
//!     patches: vec![(0.45, 0.55)],
//! };
//! let r = 0.1 / 3f64.sqrt();
//! let data = ViewerData {
//!     title: "toy".into(),
//!     subtitle: String::new(),
//!     guides: [guide(150.0), guide(270.0), guide(30.0)],
//!     attachments: [150.0f64, 270.0, 30.0].map(|a| {
//!         let (s, c) = (a + 180.0).to_radians().sin_cos();
//!         [r * c, r * s]
//!     }),
//!     links: [link.clone(), link.clone(), link],
//!     time: vec![0.0],
//!     pose: vec![[0.0, 0.0, 0.0]],
//!     sliders: vec![[0.0; 3]],
//!     deviation: None,
//!     reference_sliders: None,
//! };
//! let html = viewer_html(&data).unwrap();
//! assert!(html.starts_with("<!DOCTYPE html>") && !html.contains("__FLEXPRR_DATA__"));
//! ```

mod data;
mod encode;
mod figures;
mod html;

pub use data::{GuideView, LinkView, ViewerData, ViewerError};
pub use encode::{base64, pack_f32};
pub use figures::{WorkspaceSection, machine_svg, snapshots_svg, workspace_section};
pub use flexprr_plot::decimate::{frame_indices, min_max_indices};
pub use html::{ViewerOptions, viewer_html, viewer_html_with};
