"""hairfit.compare and hairfit.export write and print what the CLI does."""

import json

import pytest

import hairfit
from conftest import DATA, run_cli

# Cheap settings: the comparison's machinery, not its accuracy.
CHEAP = ["--starts", "2", "--polish", "1", "--intervals", "linear", "--width-nodes", "64"]


def test_compare_equals_the_cli(cli, tmp_path):
    data = DATA / "azimuthal_rgb.csv"
    printed = run_cli(cli, "compare", data, "--out", tmp_path / "cli", "--no-progress", *CHEAP).stdout
    result = hairfit.compare(data, tmp_path / "py", starts=2, polish=1, intervals="linear",
                             width_nodes=64)
    expected = json.loads((tmp_path / "cli" / "compare.json").read_text())
    summary = result.pop("summary_text")
    assert summary == printed.replace(str(tmp_path / "cli"), str(tmp_path / "py"))
    for family in ("marschner", "chiang"):
        mine = json.loads((tmp_path / "py" / family / "fit.json").read_text())
        theirs = json.loads((tmp_path / "cli" / family / "fit.json").read_text())
        assert mine == theirs, family
    assert result.keys() == expected.keys()
    assert [r["family"] for r in result["ranking"]] == [r["family"] for r in expected["ranking"]]


def test_compare_takes_models_as_a_list(tmp_path):
    data = DATA / "azimuthal_rgb.csv"
    result = hairfit.compare(data, tmp_path / "py", models=["chiang", "marschner"], starts=2,
                             polish=1, intervals="linear", width_nodes=64)
    assert [m["family"] for m in result["models"]] == ["chiang", "marschner"]
    assert {r["family"] for r in result["ranking"]} == {"chiang", "marschner"}
    for region in result["regions"]:
        if region["n"] >= 3:
            assert set(region["rms"]) == {"chiang", "marschner"}, region
    with pytest.raises(hairfit.HairfitError, match="unknown model family `nope`"):
        hairfit.compare(data, tmp_path / "bad", models="marschner,nope")


def test_export_equals_the_cli(cli, tmp_path):
    fit_dir = tmp_path / "fit"
    hairfit.fit(str(DATA / "azimuthal_rgb.csv"), intervals="linear").save(fit_dir)
    text = hairfit.export(fit_dir, to="pbrt")
    assert text == run_cli(cli, "export", fit_dir, "--to", "pbrt").stdout
    assert "MakeNamedMaterial" in text


def test_engine_exports_equal_the_cli(cli, tmp_path):
    """--to unreal and --to unity through Python write the CLI's files (the JSON and the
    script beside it) from the same fit."""
    fit_dir = tmp_path / "fit"
    hairfit.fit(str(DATA / "azimuthal_rgb.csv"), intervals="linear").save(fit_dir)
    for to, script in (("unreal", ".py"), ("unity", ".cs")):
        ours, theirs = tmp_path / f"py_{to}.json", tmp_path / f"cli_{to}.json"
        summary = hairfit.export(fit_dir, to=to, output=ours)
        run_cli(cli, "export", fit_dir, "--to", to, "--output", theirs)
        assert "rms |d ln S|" in summary
        a, b = json.loads(ours.read_text()), json.loads(theirs.read_text())
        for doc in (a, b):  # the output's own name differs, nothing else
            doc.pop("script", None)
            doc.pop("material_instance", None)
        assert a == b
        assert ours.with_suffix(script).is_file() and theirs.with_suffix(script).is_file()


def test_export_allow_failed_exports_a_failed_fit_and_warns(tmp_path):
    """A fit with sane parameters whose fit.json says `failed` (a saved fit with its verdict
    tampered): refused by default with the CLI's message, exported with allow_failed=True and
    a warning that the parameters are not a fit, both to a file and as text."""
    fit_dir = tmp_path / "fit"
    hairfit.fit(str(DATA / "azimuthal_rgb.csv"), starts=2, intervals="linear").save(fit_dir)
    fit_json = fit_dir / "fit.json"
    doc = json.loads(fit_json.read_text())
    doc["verdict"] = "failed"
    doc["reasons"] = ["no progress from the start point"]
    fit_json.write_text(json.dumps(doc, indent=2))

    with pytest.raises(hairfit.HairfitError, match="verdict is failed .*--allow-failed"):
        hairfit.export(fit_dir, to="pbrt")
    target = tmp_path / "hair.pbrt"
    summary = hairfit.export(fit_dir, to="pbrt", output=target, allow_failed=True)
    assert "exported because of --allow-failed: these parameters are not a fit" in summary
    assert "verdict failed" in target.read_text()
    with pytest.warns(UserWarning, match="these parameters are not a fit"):
        text = hairfit.export(fit_dir, to="pbrt", allow_failed=True)
    assert "MakeNamedMaterial" in text and "verdict failed" in text
