"""The chapter's closed-form models (m1-m6 and the closed-loop unicycle laws) from
Python: every case of the shipped reference files against their outputs (to each file's
tolerance_hint), and the documents equal to `moma eval`'s, exactly."""

import copy
import json

import pytest

import moma
from conftest import DATA, assert_close, load_json, run_cli

CHAPTER = DATA / "chapter"
FILES = [
    "m1_unicycle", "m2_platform_planar_arm", "m3_diffdrive_kinematics",
    "m4_cart_two_link", "m5_mobile_manipulator_3d", "m6_space_manipulator",
]
# Outputs of the closed-loop control block of m5 (computed, not inputs).
CONTROL_OUTPUTS = ["x_d0", "xdot_d0", "xddot_d0", "tau_x0", "u0", "e0", "edot0", "W0"]


def inputs_only(doc):
    """The reference document without what the evaluator computes, so nothing is echoed."""
    doc = copy.deepcopy(doc)
    for c in doc["cases"]:
        c.pop("outputs", None)
        if "trajectory" in c:
            c["trajectory"] = {"t": c["trajectory"]["t"]}
        if "control" in c:
            for k in CONTROL_OUTPUTS:
                c["control"].pop(k, None)
            c["control"]["closed_loop"] = {"t": c["control"]["closed_loop"]["t"]}
        if "trajectories" in c:
            c["trajectories"] = {
                k: {"t": v["t"], "torque": v["torque"], "qdot0": v["qdot0"]}
                for k, v in c["trajectories"].items()
            }
        if "joint_loop" in c:
            c["joint_loop"].pop("delta_psi", None)
    return doc


def test_models_are_listed():
    assert moma.chapter_models() == FILES + ["unicycle_control"]


@pytest.mark.parametrize("name", FILES)
def test_chapter_reference_cases(name):
    ref = load_json(CHAPTER / f"{name}.json")
    hint = ref["tolerance_hint"]
    got = moma.eval_cases(inputs_only(ref))
    assert len(got["cases"]) == len(ref["cases"]) >= 5
    for g, want in zip(got["cases"], ref["cases"]):
        assert_close(g["outputs"], want["outputs"], rtol=hint["algebraic_rel"],
                     atol=hint["algebraic_rel"], path=f"{name} {want['id']} outputs")
        for key in ("trajectory", "trajectories", "control", "joint_loop"):
            if key in want:
                assert_close(g[key], want[key], rtol=0.0, atol=hint["trajectory_abs"],
                             path=f"{name} {want['id']} {key}")


@pytest.mark.parametrize("name", FILES + ["unicycle_control"])
def test_documents_equal_moma_eval(moma_bin, name, tmp_path):
    src = DATA / ("control" if name == "unicycle_control" else "chapter") / f"{name}.json"
    doc = inputs_only(load_json(src)) if name != "unicycle_control" else load_json(src)
    path = tmp_path / "cases.json"
    path.write_text(json.dumps(doc))
    cli = run_cli(moma_bin, "eval", path)
    assert moma.eval_cases(path) == cli
    assert moma.eval_cases(str(path)) == cli
    assert moma.eval_cases(doc) == cli
    # one case at a time, by canonical name or alias, is the document's case
    short = name if name == "unicycle_control" else name.split("_")[0]
    assert moma.eval_case(short, doc["cases"][0]) == cli["cases"][0]
    tight = run_cli(moma_bin, "eval", path, "--tol", "1e-9")
    assert moma.eval_cases(doc, tol=1e-9) == tight


def test_errors_name_the_file_case_and_field(tmp_path):
    with pytest.raises(moma.MomaError, match="cannot read case file"):
        moma.eval_cases(tmp_path / "missing.json")
    bad = tmp_path / "bad.json"
    bad.write_text("{")
    with pytest.raises(moma.MomaError, match="bad.json: malformed JSON"):
        moma.eval_cases(bad)
    doc = inputs_only(load_json(CHAPTER / "m1_unicycle.json"))
    del doc["cases"][0]["params"]
    with pytest.raises(moma.MomaError, match=f"case {doc['cases'][0]['id']}: .*params"):
        moma.eval_cases(doc)
    with pytest.raises(moma.MomaError, match="unknown model 'm9'"):
        moma.eval_case("m9", {})
    with pytest.raises(moma.MomaError, match="tol must be in"):
        moma.eval_cases(doc, tol=1e-20)
    d2 = inputs_only(load_json(CHAPTER / "m1_unicycle.json"))
    key = next(iter(d2["cases"][0]["params"]))
    d2["cases"][0]["params"][key] = float("nan")
    with pytest.raises(moma.MomaError, match=rf"doc.cases\[0\].params.{key}: non-finite"):
        moma.eval_cases(d2)
    d2["cases"][0]["params"] = {0: 1.0}
    with pytest.raises(moma.MomaError, match=r"doc.cases\[0\].params: dict keys must be strings"):
        moma.eval_cases(d2)
    with pytest.raises(moma.MomaError, match="path of a case file or a dict"):
        moma.eval_cases(42)
