//! The `viewer`, `snapshots` and `machine` output kinds: a run's real results mapped to the
//! plain [`ViewerData`] of `flexprr-viewer`, which draws them (docs/viewer.md).
//!
//! The mapping, per link `i` and frame `k` (one frame per output time reached):
//!
//! - the platform pose: the commanded motion (the shared [`Samples`]); slider positions
//!   `rho_i`: the model's snapshots (the closed-form inverse kinematics of the commanded
//!   motion where the model prescribes the sliders);
//! - shapes: for a model whose deflection is linear in its coordinates, the deflection of
//!   each unit coordinate (the scene's own basis `psi_j(xi)` for the modal models) sampled
//!   at [`SHAPE_POINTS`] points, and the coordinates `eta_ij` from the integrated state, so
//!   the drawn line is the model's `w = sum_j psi_j eta_j` (the paper's eq. 1); for any other
//!   model the deflection itself at the [`SHAPE_POINTS`] points (unit shapes);
//! - axial force: the mean of the end forces `(P_B + P_C) / 2` (the force at mid-link for
//!   the linear distribution of model.md section 5) of the model's own snapshots
//!   ([`SceneModel::snapshot`]): the scene's axial model along the motion (KED), or the
//!   actual chord forces (coupled, nonlinear);
//! - first-mode frequency and buckling: the lowest eigenvalue `omega^2` of the KED
//!   stiffness along the motion ([`FrequencyHistory`]); where `omega^2 <= 0` the frequency
//!   is drawn as 0 and the interval is a buckling interval;
//! - a model whose platform follows the links (coupled, nonlinear): the platform deviation
//!   `(dx, dy, dphi)` from the commanded pose, from its snapshots;
//! - actuated sliders: the model's sliders, and the commanded ones (the samples' inverse
//!   kinematics) as the reference drawn beside them.

use flexprr_dynamics::{DynamicsError, FrequencyHistory, MachineSnapshot, ModalSystem, SceneModel};
use flexprr_integrators::Solution;
use flexprr_scene::{OutputKind, Scene};
use flexprr_viewer::{GuideView, LinkView, ViewerData, ViewerError, frame_indices};

use crate::error::RunError;
use crate::samples::Samples;

/// Points along each link at which the mode shapes are sampled for the viewer.
pub const SHAPE_POINTS: usize = 41;

/// Largest number of path points drawn in `machine.svg`.
const MACHINE_PATH_POINTS: usize = 4000;

/// Nodes per axis of the workspace section in `machine.svg`.
const MACHINE_GRID: usize = 241;

/// A viewer failure as a run error naming the output.
fn figure_error(file: &str, e: ViewerError) -> RunError {
    RunError::Figure {
        file: file.to_string(),
        source: e,
    }
}

/// The guides and platform joints of the scene's machine, as drawn.
fn machine_views(scene: &Scene) -> ([GuideView; 3], [[f64; 2]; 3]) {
    let legs = &scene.machine.geometry.legs;
    let guides = std::array::from_fn(|i| {
        let g = &legs[i].guide;
        GuideView {
            anchor: [g.anchor.x, g.anchor.y],
            direction: [g.direction.x, g.direction.y],
            travel: g.travel,
        }
    });
    let attachments = std::array::from_fn(|i| [legs[i].attachment.x, legs[i].attachment.y]);
    (guides, attachments)
}

/// A basis name without its `, r = N` suffix (the page states the number of modes).
fn basis_name(name: &str) -> String {
    name.split(", r =").next().unwrap_or(name).to_string()
}

/// Shapes `[shape][point]` and coordinates `[frame][shape]` of one link, as
/// [`LinkView::mode_shapes`] and [`LinkView::modal`] hold them.
type ShapesAndCoordinates = (Vec<Vec<f64>>, Vec<Vec<f64>>);

/// The shapes and coordinates of link `i` for the first `n` frames of `solution`: the
/// deflection of each unit coordinate at `xi` and the coordinates, for a model whose
/// deflection is linear in them; otherwise unit shapes and the deflection itself at `xi`.
fn link_shapes(
    model: &dyn SceneModel,
    solution: &Solution,
    n: usize,
    i: usize,
    xi: &[f64],
) -> Result<ShapesAndCoordinates, DynamicsError> {
    if model.linear_deflection() {
        let range = model.link_range(i);
        let mut unit = vec![0.0; model.dim()];
        let mut shapes = Vec::with_capacity(range.len());
        for j in range.clone() {
            unit[j] = 1.0;
            let shape = xi
                .iter()
                .map(|&x| model.deflection(0.0, i, x, &unit))
                .collect::<Result<Vec<_>, _>>();
            unit[j] = 0.0;
            shapes.push(shape?);
        }
        let coordinates = (0..n)
            .map(|k| solution.y(k)[range.clone()].to_vec())
            .collect();
        return Ok((shapes, coordinates));
    }
    let shapes = (0..xi.len())
        .map(|p| {
            (0..xi.len())
                .map(|q| if p == q { 1.0 } else { 0.0 })
                .collect()
        })
        .collect();
    let deflections = (0..n)
        .map(|k| {
            xi.iter()
                .map(|&x| model.deflection(solution.t[k], i, x, solution.y(k)))
                .collect::<Result<Vec<_>, _>>()
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok((shapes, deflections))
}

/// The viewer data of a run: `n` frames at the solution's first `n` output times, where
/// `n` is the number of output times the samples, the solution and the model's snapshots
/// reached.
///
/// `hist` is the run's frequency history when `frequencies` was requested (reused when it
/// covers the frames); otherwise it is sampled here from `ked`.
///
/// # Errors
/// The frequency history or the model's deflection failed (with its time).
pub(crate) fn viewer_data(
    scene: &Scene,
    samples: &Samples,
    model: &dyn SceneModel,
    solution: &Solution,
    snapshots: &[MachineSnapshot],
    ked: &mut ModalSystem,
    hist: Option<&FrequencyHistory>,
) -> Result<ViewerData, RunError> {
    let n = solution.len().min(samples.len()).min(snapshots.len());
    let time = solution.t[..n].to_vec();
    let sampled;
    let hist = match hist {
        Some(h) if h.t.len() >= n => h,
        _ => {
            sampled = FrequencyHistory::sample(ked, &time)?;
            &sampled
        }
    };
    let machine = model.machine();
    let xi: Vec<f64> = (0..SHAPE_POINTS)
        .map(|j| j as f64 / (SHAPE_POINTS - 1) as f64)
        .collect();
    let mut links = Vec::with_capacity(3);
    for (i, link) in machine.links.iter().enumerate() {
        let (mode_shapes, modal) = link_shapes(model, solution, n, i, &xi)?;
        let axial_force = snapshots[..n]
            .iter()
            .map(|p| 0.5 * (p.axial_force_b[i] + p.axial_force_c[i]))
            .collect();
        let first_frequency = hist.omega_squared[i].first().map_or_else(
            || vec![0.0; n],
            |w2| {
                w2[..n]
                    .iter()
                    .map(|w| w.max(0.0).sqrt() / std::f64::consts::TAU)
                    .collect()
            },
        );
        let buckling = hist
            .buckling
            .iter()
            .filter(|b| b.link == i)
            .map(|b| (b.t_start, b.t_end))
            .collect();
        links.push(LinkView {
            length: link.length(),
            basis: basis_name(&link.basis.name()),
            xi: xi.clone(),
            mode_shapes,
            modal,
            axial_force,
            first_frequency,
            buckling,
            patches: scene
                .patches
                .iter()
                .filter(|p| p.link == i)
                .map(|p| (p.xi_start, p.xi_end))
                .collect(),
        });
    }
    let links: [LinkView; 3] = links.try_into().map_err(|found: Vec<LinkView>| {
        figure_error(
            "viewer.html",
            ViewerError::Length {
                field: "links".into(),
                found: found.len(),
                expected: 3,
            },
        )
    })?;
    let deviation = model
        .platform_follows_links()
        .then(|| snapshots[..n].iter().map(|p| p.pose_deviation()).collect());
    let pose = samples.motions[..n]
        .iter()
        .map(|m| [m.pose.x, m.pose.y, m.pose.phi])
        .collect();
    let sliders = snapshots[..n]
        .iter()
        .map(|p| p.sliders.map(|s| s.position))
        .collect();
    // Actuated sliders: the commanded ones (the inverse kinematics) beside the actual ones.
    let reference_sliders = snapshots[..n]
        .first()
        .is_some_and(|p| p.actuators.is_some())
        .then(|| {
            samples.states[..n]
                .iter()
                .map(|s| s.legs.map(|l| l.rho))
                .collect()
        });
    let (guides, attachments) = machine_views(scene);
    let f = &scene.formulation;
    let subtitle = format!(
        "{} model, {} formulation, axial force {}; {} rtol {:e}",
        model.kind(),
        f.name(),
        scene.axial_model.name(),
        scene.method.name(),
        scene.options.rtol,
    );
    Ok(ViewerData {
        title: scene.name.clone(),
        subtitle,
        guides,
        attachments,
        links,
        time,
        pose,
        sliders,
        deviation,
        reference_sliders,
    })
}

/// Number of panels of `snapshots.svg`.
const SNAPSHOTS: usize = 4;

/// Instants of `snapshots.svg`, in time order: the frame with the largest deflection of
/// any link, then greedily the frame whose platform position is farthest from those
/// already chosen (farthest-point sampling; the earliest frame wins a tie). The panels
/// thus show distinct poses for any path, even when the run spans whole periods of a
/// periodic motion (equally spaced instants would then repeat one pose).
pub(crate) fn snapshot_times(data: &ViewerData) -> Vec<f64> {
    let n = data.frames();
    let largest = |k: usize| {
        data.links
            .iter()
            .flat_map(|link| (0..link.xi.len()).map(move |j| link.deflection(k, j).abs()))
            .fold(0.0, f64::max)
    };
    let mut chosen = vec![(0..n).fold(
        0,
        |best, k| {
            if largest(k) > largest(best) { k } else { best }
        },
    )];
    let distance = |a: usize, b: usize| {
        (data.pose[a][0] - data.pose[b][0]).hypot(data.pose[a][1] - data.pose[b][1])
    };
    let mut nearest: Vec<f64> = (0..n).map(|k| distance(k, chosen[0])).collect();
    while chosen.len() < SNAPSHOTS.min(n) {
        let next = (0..n).fold(
            0,
            |best, k| if nearest[k] > nearest[best] { k } else { best },
        );
        if nearest[next] <= 0.0 {
            break;
        }
        chosen.push(next);
        for (k, d) in nearest.iter_mut().enumerate() {
            *d = d.min(distance(k, next));
        }
    }
    chosen.sort_unstable();
    chosen.into_iter().map(|k| data.time[k]).collect()
}

/// `viewer.html` and `snapshots.svg` of `data`, as requested by the scene.
///
/// # Errors
/// Data the viewer refuses (naming the field and index), or a drawing failure.
pub(crate) fn viewer_files(
    scene: &Scene,
    data: &ViewerData,
) -> Result<Vec<(String, String)>, RunError> {
    let mut files = Vec::new();
    if scene.outputs.contains(&OutputKind::Viewer) {
        let html = flexprr_viewer::viewer_html(data).map_err(|e| figure_error("viewer.html", e))?;
        files.push(("viewer.html".to_string(), html));
    }
    if scene.outputs.contains(&OutputKind::Snapshots) {
        let svg = flexprr_viewer::snapshots_svg(data, &snapshot_times(data), None)
            .map_err(|e| figure_error("snapshots.svg", e))?;
        files.push(("snapshots.svg".to_string(), svg));
    }
    Ok(files)
}

/// `machine.svg`: the scene's machine, its reachable workspace at the path's first
/// orientation with the type-II locus, and the path at the output times (at most
/// 4000 points, a uniform stride).
///
/// # Errors
/// A first pose the machine cannot assemble in, or a drawing failure.
pub(crate) fn machine_file(scene: &Scene, samples: &Samples) -> Result<(String, String), RunError> {
    let path: Vec<[f64; 3]> = frame_indices(samples.len(), MACHINE_PATH_POINTS)
        .into_iter()
        .map(|k| {
            let p = &samples.motions[k].pose;
            [p.x, p.y, p.phi]
        })
        .collect();
    let title = format!("{}: machine and path", scene.name);
    let svg = flexprr_viewer::machine_svg(&scene.machine.geometry, &path, &title, MACHINE_GRID)
        .map_err(|e| figure_error("machine.svg", e))?;
    Ok(("machine.svg".to_string(), svg))
}
