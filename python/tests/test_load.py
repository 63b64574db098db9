"""hairfit.load reads what `hairfit load` reads and reports the same."""

import json

import numpy as np

import hairfit
from conftest import DATA, run_cli

SCAN = dict(columns="phi_r,theta_r,radiance", fixed={"theta_i": 20, "phi_i": 0}, missing="?",
            map="theta_r=90-x")


def test_scan_report_equals_the_cli(cli):
    path = DATA / "scan_example.txt"
    d = hairfit.load(path, **SCAN)
    expected = json.loads(run_cli(
        cli, "load", path, "--columns", "phi_r,theta_r,radiance", "--fixed",
        "theta_i=20,phi_i=0", "--missing", "?", "--map", "theta_r=90-x", "--json").stdout)
    assert d.report == expected
    assert d.report["rows_read"] == 169 and d.rows_kept == 167 == len(d)
    assert d.rejected["missing_value"]["first_lines"] == [152, 165]
    assert d.report_text == run_cli(
        cli, "load", path, "--columns", "phi_r,theta_r,radiance", "--fixed",
        "theta_i=20,phi_i=0", "--missing", "?", "--map", "theta_r=90-x").stdout
    assert np.all(d.theta_i == 20) and d.radiance.shape == (167, 1)
    assert d.channels == ["radiance"] and d.sigma is None


def test_csv_arrays_round_trip():
    path = DATA / "azimuthal_rgb.csv"
    d = hairfit.load(path)
    assert d.radiance.shape == (360, 3) and d.channels == ["r", "g", "b"]
    rows = np.loadtxt(path, delimiter=",", comments="#", skiprows=3)
    np.testing.assert_array_equal(d.theta_i, rows[:, 0])
    np.testing.assert_array_equal(d.phi_r, rows[:, 3])
    np.testing.assert_array_equal(d.radiance, rows[:, 4:])
    rad = d.angles_rad()
    np.testing.assert_array_equal(rad[0], np.deg2rad(rows[:, 0]))
