//! What the examples that run the paper's scene share: the scene text and link 1's
//! mid-point deflections of a run. A module of the examples (`mod common;`), not an example
//! of its own.

use flexprr_scene::Scene;

/// The paper's scene at 20 Hz over 0.05 s (paper formulation, three sine modes per link),
/// deflections only, named `name`, with the model kind `coupling` and the method `method`
/// at rtol 1e-10.
pub fn paper_scene_text(name: &str, coupling: &str, method: &str) -> String {
    format!(
        r#"name = "{name}"

[links]
length = 0.2
modes = 3
material = {{ youngs_modulus = 7.3e10, density = 2770.0 }}
section = {{ kind = "uniform", thickness = 0.002, height = 0.03 }}
basis = {{ kind = "sine" }}

[trajectory]
kind = "circle"
frequency = 20.0

[model]
formulation = "paper"
coupling = "{coupling}"

[integrator]
method = "{method}"
rtol = 1e-10
atol = 1e-14

[time]
end = 0.05
output_step = 0.0005

[output]
requests = ["deflections"]
plots = false
"#
    )
}

/// Link 1's mid-point deflections of a run of `scene`.
pub fn link1_deflections(scene: &Scene) -> Vec<f64> {
    let result = flexprr_run::run(scene, &mut |_| {}).unwrap_or_else(|e| panic!("run: {e}"));
    let table = result
        .tables
        .iter()
        .find(|t| t.name == "deflections")
        .expect("a deflections table");
    let header = table
        .headers()
        .into_iter()
        .find(|c| c.starts_with("w_1_"))
        .expect("a link 1 column");
    table.column(&header).expect("the column").to_vec()
}

/// The largest `|a_i - b_i|`.
pub fn max_difference(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}
