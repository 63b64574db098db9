"""hairfit.families and hairfit.export_targets list what the command line's help lists, from the
same registry, and every name they give is one model= or to= accepts."""

import inspect

import pytest

import hairfit
from conftest import run_cli


def test_families_are_the_help_s_in_its_order(cli):
    families = hairfit.families()
    # `hairfit fit --help` writes `--model`'s list from the registry: `name: citation; ...`.
    listed = "; ".join(f"{f['name']}: {f['citation']}" for f in families)
    assert listed in run_cli(cli, "fit", "--help").stdout
    assert len({f["name"] for f in families}) == len(families) >= 6
    # The first is the default family, here as on the command line.
    assert inspect.signature(hairfit.fit).parameters["model"].default == families[0]["name"]
    for f in families:
        assert f["title"] and f["citation"] and f["parameters"], f
        assert f["terms"] is None or all(isinstance(t, str) and t for t in f["terms"]), f


def test_every_family_is_a_model_the_package_takes():
    # A listed name passes the model= check and fails on the (empty) parameters instead.
    for f in hairfit.families():
        with pytest.raises(hairfit.HairfitError) as err:
            hairfit.eval_columns({}, model=f["name"])
        assert "invalid value" not in str(err.value), (f["name"], err.value)
    with pytest.raises(hairfit.HairfitError) as err:
        hairfit.eval_columns({}, model="nope")
    # The refusal lists the same names, in the same order.
    names = ", ".join(f["name"] for f in hairfit.families())
    assert "invalid value 'nope'" in str(err.value) and names in str(err.value), err.value


def test_export_targets_are_the_help_s_and_each_is_accepted(cli, tmp_path):
    targets = hairfit.export_targets()
    names = [t["name"] for t in targets]
    help_text = run_cli(cli, "export", "--help").stdout
    assert ", ".join(f"{t['name']} ({t['program']})" for t in targets) in help_text
    for t in targets:
        assert t["extension"] and t["file_kind"], t
        # A known target passes the option check and fails on the missing fit instead.
        with pytest.raises(hairfit.HairfitError) as err:
            hairfit.export(tmp_path / "no-fit", to=t["name"], output=tmp_path / f"x.{t['extension']}")
        assert "unknown export target" not in str(err.value), (t, err.value)
    with pytest.raises(hairfit.HairfitError, match=" or ".join([", ".join(names[:-1]), names[-1]])):
        hairfit.export(tmp_path / "no-fit", to="nope")
