"""Bad input raises hairfit.HairfitError with the message the CLI prints."""

import json

import pytest

import hairfit
from conftest import DATA, cli_error


def test_malformed_csv_names_file_line_column(cli, tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("theta_i,phi_i,theta_r,phi_r,radiance\n10,0,5,30,1.5\n10,0,5,3x0,1.2\n")
    expected = cli_error(cli, "load", bad)
    assert ":3:" in expected
    with pytest.raises(hairfit.HairfitError) as e:
        hairfit.load(bad)
    assert str(e.value) == expected
    assert isinstance(e.value, ValueError)
    with pytest.raises(hairfit.HairfitError) as e:
        hairfit.fit(str(bad))
    assert str(e.value) == cli_error(cli, "fit", bad, "--out", tmp_path / "out")


def test_missing_file(cli, tmp_path):
    missing = tmp_path / "nope.csv"
    with pytest.raises(hairfit.HairfitError) as e:
        hairfit.load(missing)
    assert str(e.value) == cli_error(cli, "load", missing)


def test_parameter_file_errors(cli, tmp_path):
    angles = DATA / "example_angles.csv"
    domain = tmp_path / "domain.json"
    params = json.loads((DATA / "example_params.json").read_text())
    params["eccentricity"] = 7.0
    domain.write_text(json.dumps(params))
    syntax = tmp_path / "syntax.json"
    syntax.write_text('{"eta": 1.55,\n "sigma_a": [0.2,, 0.4]}\n')
    for path in (domain, syntax):
        expected = cli_error(cli, "eval", "--params", path, "--input", angles)
        with pytest.raises(hairfit.HairfitError) as e:
            hairfit.eval(path, [10], [0], [5], [30])
        assert str(e.value) == expected


def test_fit_option_errors(cli, tmp_path):
    data = DATA / "azimuthal_rgb.csv"
    cases = [
        (dict(fix={"no_such": 1}), ["--fix", "no_such=1"]),
        (dict(free=["beta_r_deg"]), ["--free", "beta_r_deg"]),
        (dict(starts=0), ["--starts", "0"]),
        (dict(model="chiang", lobes="R"), ["--model", "chiang", "--lobes", "R"]),
    ]
    for kwargs, flags in cases:
        expected = cli_error(cli, "fit", data, "--out", tmp_path / "o", *flags)
        with pytest.raises(hairfit.HairfitError) as e:
            hairfit.fit(str(data), **kwargs)
        assert str(e.value) == expected, kwargs


def test_unknown_option_value_is_a_hairfit_error():
    with pytest.raises(hairfit.HairfitError, match="unknown loss `bogus`"):
        hairfit.fit(str(DATA / "azimuthal_rgb.csv"), loss="bogus")


def test_fit_json_given_as_parameters(cli, tmp_path):
    out = tmp_path / "fit"
    hairfit.fit(str(DATA / "azimuthal_rgb.csv"), intervals="linear").save(out)
    expected = cli_error(cli, "eval", "--params", out / "fit.json", "--input",
                         DATA / "example_angles.csv")
    with pytest.raises(hairfit.HairfitError) as e:
        hairfit.eval(out / "fit.json", [10], [0], [5], [30])
    assert str(e.value) == expected and "params.json" in expected


def test_array_errors_name_the_array():
    with pytest.raises(hairfit.HairfitError, match=r"radiance\[1, 0\] = NaN is not finite"):
        hairfit.data([10, 10], [0, 0], [5, 6], [0, 0], [1.0, float("nan")])
    with pytest.raises(hairfit.HairfitError, match=r"sigma\[0, 0\] = -1 must be a finite number > 0"):
        hairfit.data([10], [0], [5], [0], [1.0], sigma=-1.0)
