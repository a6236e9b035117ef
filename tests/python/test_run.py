"""flexprr.run against the CLI: the same scene gives the same numbers under the same names."""

import csv
import json
import pathlib

import numpy as np
import pytest

import flexprr


def read_csv(path: pathlib.Path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    data = np.array([[float(v) for v in r] for r in body])
    return header, data


@pytest.fixture(scope="module")
def paper_result(root):
    return flexprr.run(flexprr.Scene.load(root / "configs" / "paper_f20.toml"))


def test_tables_equal_the_cli_csv_files(paper_result, paper_cli_out):
    csv_files = {p.stem for p in paper_cli_out.glob("*.csv")}
    # every table is a CSV of the CLI; the CLI adds only Table I (table1.csv, from frequencies)
    assert set(paper_result.tables) == csv_files - {"table1"}
    for name in paper_result.tables:
        header, data = read_csv(paper_cli_out / f"{name}.csv")
        table = paper_result.table(name)
        assert table.columns == header, name
        assert len(table) == data.shape[0], name
        # the CSV is printed with a finite number of digits: agree to that precision
        np.testing.assert_allclose(table.to_numpy(), data, rtol=1e-9, atol=1e-300, err_msg=name)
        for j, column in enumerate(header):
            np.testing.assert_allclose(table[column], data[:, j], rtol=1e-9, atol=1e-300)


def test_summary_equals_summary_json(paper_result, paper_cli_out):
    cli = json.loads((paper_cli_out / "summary.json").read_text())
    py = paper_result.summary
    assert py["status"] == cli["status"] == "ok"

    # wall-clock entries differ between two runs; everything else is the same
    def strip(v):
        if isinstance(v, dict):
            return {k: strip(x) for k, x in v.items() if "wall" not in k and "time_s" != k}
        if isinstance(v, list):
            return [strip(x) for x in v]
        return v

    a, b = strip(py), strip(cli)
    assert a.keys() == b.keys()
    np.testing.assert_equal(json.loads(json.dumps(a)), b)


def test_stats_are_consistent(paper_result):
    s = paper_result.stats
    assert s["integrated"] is True
    assert s["steps"] > 0 and s["rhs_evaluations"] >= s["steps"]
    defl = paper_result.table("deflections")
    mid = [c for c in defl.columns if c != "t_s"]
    peak = max(np.max(np.abs(defl[c])) for c in mid)
    # the run's own maximum is over accepted steps, the table samples output times only
    assert s["max_deflection_m"] >= peak * (1 - 1e-9)


def test_table_one_lists_the_unloaded_frequency(paper_result):
    text = paper_result.table_one
    assert text is not None
    mode1 = next(line for line in text.splitlines() if line.startswith("| mode 1"))
    nominal = float(mode1.split("|")[2])
    # closed form of the pinned-pinned link without axial force: (pi/l)^2 sqrt(EI/rhoA) / (2 pi)
    e, rho, t, h, length = 7.3e10, 2770.0, 0.002, 0.03, 0.2
    f1 = (np.pi / length) ** 2 * np.sqrt(e * h * t**3 / 12 / (rho * t * h)) / (2 * np.pi)
    assert nominal == pytest.approx(f1, abs=0.05)  # printed with one decimal


def test_to_pandas_matches_to_numpy(paper_result):
    pd = pytest.importorskip("pandas")
    t = paper_result.table("kinematics")
    df = t.to_pandas()
    assert isinstance(df, pd.DataFrame)
    assert list(df.columns) == t.columns
    np.testing.assert_array_equal(df.to_numpy(), t.to_numpy())


def test_missing_table_is_a_key_error(root):
    scene = flexprr.Scene.load(root / "configs" / "paper_f20.toml")
    scene.set("output.requests", ["kinematics"]).set("output.plots", False)
    r = flexprr.run(scene)
    assert r.tables == ["kinematics"]
    with pytest.raises(KeyError, match="deflections"):
        r.table("deflections")
    assert r.stats["integrated"] is False


def test_scene_sources_agree(root):
    path = root / "configs" / "paper_f20.toml"
    a = flexprr.Scene.load(path)
    b = flexprr.Scene.from_toml(path.read_text(), name="paper_f20")
    c = flexprr.Scene.from_dict(a.to_dict(), name="paper_f20")
    for s in (a, b, c):
        s.set("output.requests", ["kinematics", "driving_forces"]).set("output.plots", False)
    ra, rb, rc = (flexprr.run(s) for s in (a, b, c))
    for name in ("kinematics", "driving_forces"):
        np.testing.assert_array_equal(ra.table(name).to_numpy(), rb.table(name).to_numpy())
        np.testing.assert_array_equal(ra.table(name).to_numpy(), rc.table(name).to_numpy())


def test_run_many_equals_run(root):
    base = flexprr.Scene.load(root / "configs" / "paper_f20.toml")
    base.set("output.requests", ["deflections"]).set("output.plots", False)
    base.set("time.end", 0.05)
    scenes = [base.copy().set("links.section.thickness", t) for t in (2e-3, 3e-3)]
    many = flexprr.run_many(scenes, threads=2)
    for s, r in zip(scenes, many):
        single = flexprr.run(s)
        np.testing.assert_array_equal(r.table("deflections").to_numpy(), single.table("deflections").to_numpy())
