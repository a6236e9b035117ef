//! Kinematics of the 3-PRR from Python, vectorised over arrays of poses: inverse kinematics
//! (closure `|C_i - B_i| = l_i`, Gosselin & Angeles 1990), forward kinematics (Newton on the
//! closure equations) and the singularity measures (`flexprr_kinematics`).

use flexprr_kinematics::{Circle, Geometry, PlatformMotion, Pose, Trajectory};
use numpy::ndarray::{Array1, Array2, ArrayViewD, Axis, Ix1};
use numpy::{AllowTypeChange, IntoPyArray, PyArrayLikeDyn};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{KinematicsError, scene_error};
use crate::progress::detached;
use crate::scene::PyScene;

/// The scene's geometry and nominal pose (its trajectory's pose at the first output time),
/// or the paper's machine and the start of the paper's circle, `(0, 0, 45 deg)`.
fn machine(py: Python<'_>, scene: Option<&PyScene>) -> PyResult<(Geometry, Pose)> {
    match scene {
        None => {
            let circle = Circle::paper(1.0).map_err(|e| PyValueError::new_err(e.to_string()))?;
            Ok((Geometry::paper(), circle.motion(0.0).pose))
        }
        Some(s) => {
            let s = s.clone();
            let built = detached(py, None, 1.0, move |_| s.build())?.map_err(scene_error)?;
            let t0 = built.output_times.first().copied().unwrap_or(0.0);
            let nominal = built.trajectory.motion(t0).pose;
            Ok((built.machine.geometry, nominal))
        }
    }
}

/// Rows of three from a `(3,)` or `(n, 3)` array; `true` when the input was one row.
fn rows3(name: &str, a: &ArrayViewD<'_, f64>) -> PyResult<(Vec<[f64; 3]>, bool)> {
    match a.shape() {
        [3] => {
            let v = a
                .view()
                .into_dimensionality::<Ix1>()
                .map_err(|e| PyValueError::new_err(e.to_string()))?;
            Ok((vec![[v[0], v[1], v[2]]], true))
        }
        [_, 3] => Ok((
            a.axis_iter(Axis(0)).map(|r| [r[0], r[1], r[2]]).collect(),
            false,
        )),
        shape => Err(PyValueError::new_err(format!(
            "{name}: expected shape (3,) or (n, 3), got {shape:?}"
        ))),
    }
}

fn kin_error(index: usize, single: bool, e: &flexprr_kinematics::KinematicsError) -> PyErr {
    let err = if single {
        KinematicsError::new_err(e.to_string())
    } else {
        KinematicsError::new_err(format!("pose {index}: {e}"))
    };
    Python::attach(|py| match err.value(py).setattr("index", index) {
        Ok(()) => err,
        Err(e) => e,
    })
}

fn out3<'py>(py: Python<'py>, rows: Vec<[f64; 3]>, single: bool) -> PyResult<Bound<'py, PyAny>> {
    if single {
        Ok(Array1::from(rows[0].to_vec()).into_pyarray(py).into_any())
    } else {
        let n = rows.len();
        let flat: Vec<f64> = rows.into_iter().flatten().collect();
        let a = Array2::from_shape_vec((n, 3), flat)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(a.into_pyarray(py).into_any())
    }
}

/// Inverse kinematics of poses `(x, y, phi)` (m, m, rad), shape `(3,)` or `(n, 3)`, with all
/// the checks of a run (reach, slider travel, singularity thresholds). Returns a dict with
/// `rho` (slider positions, m) and `beta` (link angles, rad), each of shape `(3,)` or
/// `(n, 3)`. Raises `KinematicsError` (with `index`) at the first pose that fails. Uses the
/// scene's machine, or the paper's when `scene` is None.
#[pyfunction]
#[pyo3(signature = (poses, scene = None))]
pub fn inverse_kinematics<'py>(
    py: Python<'py>,
    poses: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
    scene: Option<PyRef<'py, PyScene>>,
) -> PyResult<Bound<'py, PyDict>> {
    let (g, _) = machine(py, scene.as_deref())?;
    let (rows, single) = rows3("poses", &poses.as_array())?;
    let solved = detached(py, None, 1.0, |_| {
        let mut rho = Vec::with_capacity(rows.len());
        let mut beta = Vec::with_capacity(rows.len());
        for (i, p) in rows.iter().enumerate() {
            let motion = PlatformMotion::at_rest(Pose::new(p[0], p[1], p[2]));
            let state = g.inverse_kinematics(&motion).map_err(|e| (i, e))?;
            rho.push(std::array::from_fn::<f64, 3, _>(|k| state.legs[k].rho));
            beta.push(std::array::from_fn::<f64, 3, _>(|k| state.legs[k].beta));
        }
        Ok((rho, beta))
    })?;
    let (rho, beta) = solved.map_err(|(i, e)| kin_error(i, single, &e))?;
    let d = PyDict::new(py);
    d.set_item("rho", out3(py, rho, single)?)?;
    d.set_item("beta", out3(py, beta, single)?)?;
    Ok(d)
}

/// Forward kinematics: the pose `(x, y, phi)` from slider positions `rho` (m), shape `(3,)`
/// or `(n, 3)`, by Newton's method on the closure equations. Newton finds the assembly mode
/// its start leads to; the start is `guess` (one pose, or one per row) when given. Without a
/// guess, the first row starts from the scene's nominal pose (its trajectory at the first
/// output time; for the paper's machine the start of its circle, `(0, 0, 45 deg)`), and
/// each further row from the previous row's solution (continuation along a path), then
/// from the nominal pose if that fails. Returns poses of the same shape; raises
/// `KinematicsError` (with `index`) at the first row that fails.
#[pyfunction]
#[pyo3(signature = (rho, guess = None, scene = None))]
pub fn forward_kinematics<'py>(
    py: Python<'py>,
    rho: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
    guess: Option<PyArrayLikeDyn<'py, f64, AllowTypeChange>>,
    scene: Option<PyRef<'py, PyScene>>,
) -> PyResult<Bound<'py, PyAny>> {
    let (g, nominal) = machine(py, scene.as_deref())?;
    let (rows, single) = rows3("rho", &rho.as_array())?;
    let guesses = match &guess {
        None => Vec::new(),
        Some(a) => rows3("guess", &a.as_array())?.0,
    };
    if guess.is_some() && guesses.len() != 1 && guesses.len() != rows.len() {
        return Err(PyValueError::new_err(format!(
            "guess: {} rows for {} rows of rho (give one guess or one per row)",
            guesses.len(),
            rows.len()
        )));
    }
    let solved = detached(py, None, 1.0, |_| {
        let mut poses: Vec<[f64; 3]> = Vec::with_capacity(rows.len());
        for (i, r) in rows.iter().enumerate() {
            let solve = |q: &Pose| g.forward_kinematics(*r, q).map(|p| [p.x, p.y, p.phi]);
            let pose = match (guesses.len(), poses.last()) {
                (0, None) => solve(&nominal),
                (0, Some(prev)) => {
                    solve(&Pose::new(prev[0], prev[1], prev[2])).or_else(|_| solve(&nominal))
                }
                (n, _) => {
                    let q = guesses[if n == 1 { 0 } else { i }];
                    solve(&Pose::new(q[0], q[1], q[2]))
                }
            };
            poses.push(pose.map_err(|e| (i, e))?);
        }
        Ok(poses)
    })?;
    let poses = solved.map_err(|(i, e)| kin_error(i, single, &e))?;
    out3(py, poses, single)
}

/// Singularity measures of poses, shape `(3,)` or `(n, 3)`: `type_i` (per leg,
/// `|cos(beta_i - alpha_i)|`, 0 at a type-I singularity) and `type_ii` (`|det N|` of the
/// normalised direct Jacobian, 0 at a type-II singularity), both in `[0, 1]`.
#[pyfunction]
#[pyo3(signature = (poses, scene = None))]
pub fn singularity<'py>(
    py: Python<'py>,
    poses: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
    scene: Option<PyRef<'py, PyScene>>,
) -> PyResult<Bound<'py, PyDict>> {
    let (g, _) = machine(py, scene.as_deref())?;
    let (rows, single) = rows3("poses", &poses.as_array())?;
    let solved = detached(py, None, 1.0, |_| {
        rows.iter()
            .enumerate()
            .map(|(i, p)| {
                g.singularity(&Pose::new(p[0], p[1], p[2]))
                    .map_err(|e| (i, e))
            })
            .collect::<Result<Vec<_>, _>>()
    })?;
    let measures = solved.map_err(|(i, e)| kin_error(i, single, &e))?;
    let d = PyDict::new(py);
    let type_ii: Vec<f64> = measures.iter().map(|m| m.type_ii).collect();
    d.set_item(
        "type_i",
        out3(py, measures.iter().map(|m| m.type_i).collect(), single)?,
    )?;
    if single {
        d.set_item("type_ii", type_ii[0])?;
    } else {
        d.set_item("type_ii", Array1::from(type_ii).into_pyarray(py))?;
    }
    Ok(d)
}
