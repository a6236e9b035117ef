"""Scene.set checks the key and the value's type at once; later errors name the key set."""

import subprocess

import pytest

import flexprr


@pytest.fixture
def paper(root):
    return flexprr.Scene.load(root / "configs" / "paper_f20.toml")


@pytest.mark.parametrize(
    "key, value, expected",
    [
        ("links.nope", 1.0, "unknown field `nope`"),
        ("nope", 1.0, "unknown field `nope`"),
        ("links.section.width", 0.1, "unknown field `width`"),
        ("links.basis.nope", 3, "nope"),
        ("links.length", "abc", 'string "abc"'),
        ("output.plots", 1, "boolean"),
        ("output.requests", ["kinematics", "nothing"], "nothing"),
        ("integrator.max_steps", 2.5, "floating point"),
        ("machine.alpha_deg", [1.0, 2.0], "3"),
        ("model.formulation", "papers", "papers"),
        ("trajectory.kind", "line", "set the whole table"),
        ("links", 5, "links"),
    ],
)
def test_bad_key_or_type_is_refused_at_set_and_the_scene_is_unchanged(paper, key, value, expected):
    before = paper.to_dict()
    with pytest.raises(flexprr.SceneError) as info:
        paper.set(key, value)
    e = info.value
    assert e.key == key
    assert expected in str(e)
    assert str(e).startswith(f"{key}: ") and "\n" not in str(e)
    # the value was never written in a file: no location
    assert (e.file, e.line, e.column) == (None, None, None)
    assert paper.to_dict() == before
    assert paper.changed_keys == []
    # the same check through item assignment
    with pytest.raises(flexprr.SceneError):
        paper[key] = value
    paper.validate()


def test_numbers_follow_the_schema(paper):
    paper.set("machine.platform_inertia", 1)  # absent from the file; the schema wants a float
    assert isinstance(paper["machine.platform_inertia"], float)
    paper.set("integrator.max_steps", 1e6)  # an integral float where the schema wants an int
    assert paper["integrator.max_steps"] == 1_000_000 and isinstance(paper["integrator.max_steps"], int)
    paper.validate()


def test_a_range_error_after_set_names_the_key_and_no_generated_line(paper):
    paper.set("links.section.thickness", -1.0)  # a float: accepted by set, refused by validation
    with pytest.raises(flexprr.SceneError) as info:
        paper.validate()
    e = info.value
    assert e.key == "links.section.thickness"
    assert (e.file, e.line) == (None, None)
    assert "Scene.set" in str(e) and "\n" not in str(e)
    with pytest.raises(flexprr.SceneError) as again:
        flexprr.run(paper)
    assert again.value.key == "links.section.thickness"


def test_an_error_elsewhere_is_located_in_the_users_file(tmp_path, root, cli):
    text = (root / "configs" / "paper_f20.toml").read_text().replace("rtol = ", "rtol = -", 1)
    assert "rtol = -" in text
    path = tmp_path / "bad_rtol.toml"
    path.write_text(text)
    check = subprocess.run([str(cli), "check", str(path)], capture_output=True, text=True)
    assert check.returncode == 2
    scene = flexprr.Scene.load(path).set("links.length", 0.21)
    with pytest.raises(flexprr.SceneError) as info:
        scene.validate()
    e = info.value
    assert e.key == "integrator.rtol"
    # the line the user wrote, as flexprr check reports it
    assert e.file == str(path)
    assert e.line == text.splitlines().index(next(l for l in text.splitlines() if "rtol = -" in l)) + 1
    assert f"{path}:{e.line}:" in check.stderr
    assert "links.length" in str(e)  # says the scene was changed


def test_a_scene_from_a_dict_is_built_key_by_key(paper):
    scene = flexprr.Scene.from_dict({}, name="built")
    for key in ("trajectory", "time", "output"):
        scene.set(key, paper[key])
    scene.set("output.requests", ["kinematics"]).set("output.plots", False)
    scene.validate()
    with pytest.raises(flexprr.SceneError):
        scene.set("time.nope", 1)


@pytest.mark.parametrize(
    "make, expected",
    [
        (lambda: (lambda d: (d.__setitem__("a", d), d)[1])({}), "cycle"),
        (lambda: (lambda l: (l.append(l), l)[1])([]), "cycle"),
        (lambda: _deep(100_000), "deeper than 32"),
        (lambda: 10**40, "64 bits"),
        (lambda: "\ud800", "Unicode"),
        (lambda: object(), "type object"),
        (lambda: {1: 2.0}, "keys must be strings"),
        (lambda: {1.5}, "type set"),
    ],
)
def test_values_that_are_no_scene_value_raise_a_scene_error(paper, make, expected):
    with pytest.raises(flexprr.SceneError) as info:
        paper.set("links.length", make())
    assert info.value.key.startswith("links.length")
    assert expected in str(info.value) and "\n" not in str(info.value)


def test_an_object_whose_tolist_never_ends_is_refused(paper):
    class Endless:
        def tolist(self):
            return Endless()

    with pytest.raises(flexprr.SceneError, match="deeper than"):
        paper.set("links.length", Endless())


def test_numpy_values_are_plain_values(paper):
    np = pytest.importorskip("numpy")
    paper.set("links.length", np.float64(0.2)).set("machine.alpha_deg", np.array([150, 270, 30]))
    assert paper["machine.alpha_deg"] == [150.0, 270.0, 30.0]
    paper.validate()


def _deep(levels):
    top = cur = []
    for _ in range(levels):
        nxt = []
        cur.append(nxt)
        cur = nxt
    return top


def test_control_keys_are_set_and_checked_like_any_other(root):
    """[actuators] and [control] keys through Scene.set: unknown keys, bad words and bad
    gains are refused at set; a servo built key by key runs and returns the new tables."""
    scene = flexprr.Scene.load(root / "configs" / "coupled_f20.toml")
    scene.set("control.kind", "pd")  # incomplete until kp and kd are set: that is allowed
    for key, value, expected in [
        ("control.kq", 1.0, "unknown field `kq`"),
        ("actuators.kind", "linear_motor", "linear_motor"),
    ]:
        with pytest.raises(flexprr.SceneError) as info:
            scene.set(key, value)
        assert info.value.key == key and expected in str(info.value)
    scene.set("control.kp", 200000).set("control.kd", 400)
    with pytest.raises(flexprr.SceneError) as info:
        scene.set("control.kp", -1.0)
    assert info.value.key == "control.kp" and "got -1" in str(info.value)
    scene.set("time.end", 0.01).set("output.requests", ["tracking", "actuators"])
    result = flexprr.run(scene)
    tracking = result.table("tracking")
    assert "slider_error_1_m" in tracking and "platform_error_phi_rad" in tracking
    assert "actuator_force_2_N" in result.table("actuators")
    assert result.summary["control"]["controller"] == "pd"
    assert result.summary["feasibility"] is None
    # the KED model prescribes the sliders: [control] is refused at validation, at its key
    scene.set("model.coupling", "ked")
    with pytest.raises(flexprr.SceneError) as info:
        scene.validate()
    assert info.value.key == "control" and "coupled" in str(info.value)


def test_vibration_control_keys_and_types_are_checked_at_set(root):
    """Issue 34: Scene.set accepted unknown vibration_control keys; the law's keys are now
    checked at once against the scene's patches, as validation checks them."""
    scene = flexprr.Scene.load(root / "configs" / "piezo_f20.toml")
    before = scene.to_dict()
    for key, value, expected in [
        ("vibration_control.gian", 0.01, "unknown field `gian`"),
        ("vibration_control.gain", "high", "gain"),
    ]:
        with pytest.raises(flexprr.SceneError) as info:
            scene.set(key, value)
        assert info.value.key == key and expected in str(info.value)
        assert scene.to_dict() == before
    scene.set("vibration_control.gain", 0.01)
    assert scene.get("vibration_control.gain") == 0.01
