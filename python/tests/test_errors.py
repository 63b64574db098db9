"""Bad input raises hairfit.HairfitError with the message the CLI prints."""

import json

import pytest

import hairfit
from conftest import DATA, ROOT, cli_error


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


# Mistakes a NumPy user makes, each a Python exception that names the argument and what to pass.

PARAMS = {"eta": 1.55, "sigma_a": 0.4, "alpha_r_deg": -7, "beta_r_deg": 8, "k_g": 2,
          "w_c_deg": 15, "eccentricity": 0.9}
ANGLES = ([10.0, 5.0], [0.0, 0.0], [20.0, -10.0], [30.0, 170.0])


def test_params_dict_takes_numpy_values_and_refuses_nan():
    import numpy as np

    plain = hairfit.eval(PARAMS, *ANGLES)
    # NumPy scalars and 0-d arrays are the numbers they hold (a NumPy user's natural values).
    for eta in (np.float32(1.55), np.float64(1.55), np.array(1.55)):
        same = hairfit.eval({**PARAMS, "eta": eta}, *ANGLES)
        # float32(1.55) is not 1.55: compare it against the value it holds, exactly.
        expected = hairfit.eval({**PARAMS, "eta": float(eta)}, *ANGLES)
        assert np.array_equal(same, expected)
    assert np.array_equal(hairfit.eval({**PARAMS, "eta": np.float64(1.55)}, *ANGLES), plain)
    rgb = hairfit.eval({**PARAMS, "sigma_a": np.array([0.2, 0.3, 0.5])}, *ANGLES)
    assert rgb.shape == (2, 3)
    for bad in (float("nan"), float("inf"), np.nan):
        with pytest.raises(hairfit.HairfitError, match=r"params\['eta'\] is .*finite number"):
            hairfit.eval({**PARAMS, "eta": bad}, *ANGLES)
    with pytest.raises(hairfit.HairfitError, match=r"params\['sigma_a\[1\]'\]"):
        hairfit.eval({**PARAMS, "sigma_a": [0.2, float("nan"), 0.5]}, *ANGLES)


def test_complex_arrays_are_refused_by_name():
    import numpy as np

    with pytest.raises(TypeError, match="theta_r is complex"):
        hairfit.eval(PARAMS, ANGLES[0], ANGLES[1], np.array(ANGLES[2], dtype=complex), ANGLES[3])
    with pytest.raises(TypeError, match="radiance is complex"):
        hairfit.data(*ANGLES, radiance=np.array([1.0, 2.0], dtype=complex))


def test_a_mistyped_keyword_is_a_type_error_naming_what_was_meant():
    with pytest.raises(TypeError, match=r"fit\(\) got an unexpected keyword argument 'los'; did you mean 'loss'\?"):
        hairfit.fit(DATA / "sphere_1ch.csv", los="cauchy")
    with pytest.raises(TypeError, match=r"eval\(\) got an unexpected keyword argument 'lobbes'"):
        hairfit.eval(PARAMS, *ANGLES, lobbes="R")


def test_a_negative_option_value_is_read_as_a_value(cli, tmp_path):
    # `--starts -1` would be read as an unknown flag `-1`; the value is passed as --starts=-1, so
    # the message is the one the CLI gives for that value.
    with pytest.raises(hairfit.HairfitError) as e:
        hairfit.fit(DATA / "sphere_1ch.csv", starts=-1)
    assert "invalid value '-1' for '--starts" in str(e.value)
    assert "unexpected argument" not in str(e.value)


def test_radiance_shape_and_channel_names_are_checked_against_the_samples():
    import numpy as np

    with pytest.raises(hairfit.HairfitError, match=r"looks transposed: pass radiance\.T, shape \(2, 3\)"):
        hairfit.data(*ANGLES, radiance=np.ones((3, 2)))
    with pytest.raises(hairfit.HairfitError, match="has shape \\(5, 3\\) but there are 2 samples"):
        hairfit.data(*ANGLES, radiance=np.ones((5, 3)))
    with pytest.raises(hairfit.HairfitError, match="channel name 'r' is given twice"):
        hairfit.data(*ANGLES, radiance=np.ones((2, 2)), channels=["r", "r"])
    with pytest.raises(hairfit.HairfitError, match="channels names 2 channel"):
        hairfit.data(*ANGLES, radiance=np.ones(2), channels=["r", "g"])


def test_eval_under_a_memory_cap_raises_memory_error_not_a_panic(tmp_path):
    # A child with 1.5 GB of address space: its 800 MB of angles fit, the 800 MB result does not.
    import subprocess
    import sys

    script = tmp_path / "cap.py"
    script.write_text(
        "import resource, numpy as np, hairfit\n"
        "resource.setrlimit(resource.RLIMIT_AS, (1_500_000_000, 1_500_000_000))\n"
        "a = np.full(100_000_000, 10.0)\n"
        f"p = {PARAMS!r}\n"
        "try:\n"
        "    hairfit.eval(p, a, a, a, a)\n"
        "    print('no error')\n"
        "except MemoryError as e:\n"
        "    print('MemoryError:', e)\n"
    )
    run = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    assert "MemoryError:" in run.stdout and "smaller chunks" in run.stdout, run.stdout + run.stderr
    assert "panicked" not in run.stderr and "PanicException" not in run.stdout + run.stderr


def test_fit_and_compare_under_a_memory_cap_raise_memory_error_and_the_interpreter_goes_on(tmp_path):
    # A child whose address space is capped a few MB above what it holds: the fit's vectors
    # (100k rows, 0.8-5 MB each) and compare's are refused mid-run. Each call must end as a
    # MemoryError (or succeed), never abort the interpreter (exit 134) or raise PanicException;
    # with the cap lifted, the same interpreter fits again.
    import subprocess
    import sys

    demo_data = str(ROOT / "fits" / "demo" / "data.csv")
    script = tmp_path / "cap.py"
    script.write_text(
        "import resource, numpy as np, hairfit\n"
        "vm = lambda: int(open('/proc/self/statm').read().split()[0]) * 4096\n"
        "n = 100_000\n"
        "rng = np.random.default_rng(1)\n"
        "a = [rng.uniform(-60, 60, n), np.zeros(n), rng.uniform(-60, 60, n), rng.uniform(-180, 180, n)]\n"
        f"p = {PARAMS!r}\n"
        "d = hairfit.data(*a, radiance=hairfit.eval(p, *a)[:, 0])\n"
        "calls = {'fit': lambda: hairfit.fit(d),\n"
        f"         'compare': lambda: hairfit.compare({demo_data!r}, out={str(tmp_path / 'c')!r}, models='all')}}\n"
        "for name, call in calls.items():\n"
        "    for extra_mb in ((8, 20) if name == 'fit' else (1, 4)):\n"
        "        hairfit.eval(p, [10.0], [0.0], [20.0], [30.0])  # sets the 64 MiB ballast aside again\n"
        "        resource.setrlimit(resource.RLIMIT_AS, (vm() + extra_mb * 10**6, resource.RLIM_INFINITY))\n"
        "        try:\n"
        "            call()\n"
        "            print(name, extra_mb, 'ok')\n"
        "        except MemoryError as e:\n"
        "            print(name, extra_mb, 'MemoryError:', e)\n"
        "        resource.setrlimit(resource.RLIMIT_AS, (resource.RLIM_INFINITY, resource.RLIM_INFINITY))\n"
        "print('after:', hairfit.fit(d).verdict)\n"
    )
    run = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "PanicException" not in run.stdout + run.stderr and "panicked" not in run.stderr
    assert "the system refused" in run.stdout and "Run with a higher limit" in run.stdout, run.stdout
    assert "after: good" in run.stdout, run.stdout
