"""hairfit.fit is `hairfit fit`: the same fit.json, and save() writes the same directory."""

import json
import os

import numpy as np

import hairfit
from conftest import DATA, run_cli


def cli_fit(cli, tmp_path, data, *options):
    out = tmp_path / "cli"
    run_cli(cli, "fit", data, "--out", out, *options)
    return out


def test_fit_json_equals_the_cli(cli, tmp_path):
    data = DATA / "longitudinal_rgb.csv"
    out = cli_fit(cli, tmp_path, data)
    result = hairfit.fit(str(data))
    expected = json.loads((out / "fit.json").read_text())
    # Exact equality: the same code on the same data (fit.json holds no wall-clock times).
    assert result.to_dict() == expected
    assert result.params == json.loads((out / "params.json").read_text())
    assert result.verdict == expected["verdict"] and result.reasons == expected["reasons"]
    names = [p["name"] for p in expected["parameters"]]
    assert list(result.stderr) == names
    # --intervals auto profiles this fit: the 68% and 95% intervals are there.
    assert expected["options"]["intervals"] == "profile"
    assert result.intervals and all("95" in v for v in result.intervals.values())
    corr_names, matrix = result.correlation
    assert corr_names == expected["correlation"]["names"]
    assert matrix.shape == (len(corr_names), len(corr_names))
    assert result.chi2 == expected["goodness_of_fit"]["chi2"]


def test_save_writes_what_the_cli_writes(cli, tmp_path):
    data = DATA / "azimuthal_rgb.csv"
    options = dict(fix={"alpha_r_deg": -7, "beta_r_deg": 8}, loss="huber")
    out = cli_fit(cli, tmp_path, data, "--fix", "alpha_r_deg=-7", "--fix", "beta_r_deg=8",
                  "--loss", "huber")
    result = hairfit.fit(str(data), **options)
    mine = tmp_path / "py"
    line = result.save(mine)
    assert line == f"report: {mine / 'index.html'}\n"
    assert sorted(os.listdir(mine)) == sorted(os.listdir(out))
    for name in ("fit.json", "params.json", "curves.csv"):
        assert (mine / name).read_bytes() == (out / name).read_bytes(), name
    assert set(result.timing()) >= {"wall_time_s", "stages"}


def test_fit_of_arrays_and_of_loaded_data(tmp_path):
    data = DATA / "longitudinal_rgb.csv"
    from_file = hairfit.fit(str(data), seed=3, intervals="linear")
    loaded = hairfit.load(data)
    from_loaded = hairfit.fit(loaded, seed=3, intervals="linear")
    assert from_loaded.to_dict() == from_file.to_dict()
    arrays = dict(theta_i=loaded.theta_i, phi_i=loaded.phi_i, theta_r=loaded.theta_r,
                  phi_r=loaded.phi_r, radiance=loaded.radiance, channels=loaded.channels)
    if loaded.sigma is not None:
        arrays["sigma"] = loaded.sigma
    from_arrays = hairfit.fit(arrays, seed=3, intervals="linear")
    # The same samples: the same parameters (only the file name and lines differ).
    assert from_arrays.params == from_file.params
    assert from_arrays.stderr == from_file.stderr
    assert from_arrays.to_dict()["data"]["file"] == "<arrays>"


def test_fitted_params_evaluate():
    data = DATA / "azimuthal_rgb.csv"
    result = hairfit.fit(str(data), intervals="linear")
    d = hairfit.load(data)
    s = hairfit.eval(result.params, d.theta_i, d.phi_i, d.theta_r, d.phi_r)
    scale = np.array([result.scale[c][0] for c in d.channels])
    rel = np.abs(s * scale - d.radiance) / d.radiance
    assert rel.max() < 1e-9  # the shipped azimuthal data are noise-free


def test_chiang_fit_equals_the_cli(cli, tmp_path):
    data = DATA / "azimuthal_rgb.csv"
    flags = ["--model", "chiang", "--width-nodes", "64", "--starts", "2", "--polish", "1",
             "--intervals", "linear"]
    out = cli_fit(cli, tmp_path, data, *flags)
    result = hairfit.fit(str(data), model="chiang", width_nodes=64, starts=2, polish=1,
                         intervals="linear")
    assert result.to_dict() == json.loads((out / "fit.json").read_text())
    assert result.params["model"] == "chiang"
