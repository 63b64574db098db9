"""hairfit.synth makes the bytes `hairfit synth` makes (a shipped dataset, data/README.md)."""

import json

import hairfit
from conftest import DATA, run_cli

RIG = "azimuthal:incidences=15,30,45:steps=120"
NOISE = "relative:0.02+outliers:0.01"


def test_synth_reproduces_the_cli_and_a_shipped_dataset(cli, tmp_path):
    (tmp_path / "py").mkdir()
    (tmp_path / "cli").mkdir()
    out = tmp_path / "py" / "noisy.csv"
    summary = hairfit.synth(DATA / "true_1ch.json", rig=RIG, output=out, noise=NOISE, seed=1,
                            scale=[0.8])
    cli_out = tmp_path / "cli" / "noisy.csv"
    run_cli(cli, "synth", "--params", DATA / "true_1ch.json", "--rig", RIG, "--noise", NOISE,
            "--seed", "1", "--scale", "0.8", "--output", cli_out)
    assert summary["csv"] == str(out) and summary["n_samples"] == 360
    assert summary["truth"] == str(tmp_path / "py" / "noisy.truth.json")
    assert out.read_bytes() == cli_out.read_bytes()
    assert out.read_bytes() == (DATA / "azimuthal_1ch_noisy.csv").read_bytes()
    truth = json.loads((tmp_path / "py" / "noisy.truth.json").read_text())
    expected = json.loads((tmp_path / "cli" / "noisy.truth.json").read_text())
    # The command line names this run's output file; everything else is the same.
    assert truth.pop("command_line").startswith("hairfit synth --params ")
    expected.pop("command_line")
    assert truth == expected
    assert summary["n_outliers"] == len(expected["outliers"]) > 0
