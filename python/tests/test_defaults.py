"""A keyword left out takes the core's default: the signatures only show it. These fail
when a signature, or the stub, states a default the core does not use."""

import ast
import inspect
import json
import pathlib

import era

# model.json's names of the keywords `identify` records.
RECORDED = ["hankel_factor", "integrations", "zero_lines", "pad_to", "svd", "residuals",
            "reciprocal", "weighting", "max_iterations", "added_modes", "preset"]


def shown_defaults(function):
    return {name: p.default for name, p in inspect.signature(function).parameters.items()
            if p.default is not inspect.Parameter.empty}


def test_identify_runs_with_the_defaults_it_shows():
    shown = shown_defaults(era.identify)
    found = era.identify(era.simulate_truth_model(), states=8, refine=True)
    params = json.loads(found.to_json())["parameters"]
    for name in RECORDED:
        assert params[name] == shown[name], name
    # era_dc=False: ERA, which model.json does not record.
    assert shown["era_dc"] is False and "realizer" not in params
    assert params["lowpass_hz"] is None and shown["lowpass"] is None


def test_identify_time_shows_identify_s_defaults():
    time, frf = shown_defaults(era.identify_time), shown_defaults(era.identify)
    # The time histories' own: the estimate's coherence weights OKID's refinement.
    assert time["weighting"] is None
    for name in set(time) & set(frf) - {"states", "weighting"}:
        assert time[name] == frf[name], name
    welch = shown_defaults(era.estimate_frf)
    for name in ["window", "overlap", "estimator", "detrend", "quantity"]:
        assert time[name] == welch[name], name


def test_the_stub_shows_the_same_defaults():
    stub = pathlib.Path(__file__).resolve().parents[1] / "era" / "_era.pyi"
    tree = ast.parse(stub.read_text())
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and node.name in ("identify", "estimate_frf"):
            args = node.args.args
            written = {a.arg: ast.literal_eval(d)
                       for a, d in zip(args[len(args) - len(node.args.defaults):], node.args.defaults)}
            assert written == shown_defaults(getattr(era, node.name)), node.name
