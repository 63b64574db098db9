"""hairfit.eval gives bit for bit what `hairfit eval` writes for the same angles."""

import csv
import json

import numpy as np
import pytest

import hairfit
from conftest import DATA, run_cli

PARAMS = DATA / "example_params.json"

CHIANG = {"model": "chiang", "eta": 1.55, "sigma_a": [0.2, 0.5, 1.1], "beta_m": 0.3,
          "beta_n": 0.4, "alpha_deg": 2.0}


def random_angles(n, seed=7):
    rng = np.random.default_rng(seed)
    return (
        rng.uniform(-85, 85, n),
        rng.uniform(-180, 180, n),
        rng.uniform(-85, 85, n),
        rng.uniform(-360, 360, n),
    )


def cli_eval(cli, tmp_path, angles, *options, params=PARAMS, unit="deg"):
    """`hairfit eval` on the angles written as shortest round-trip text (which the CLI parses
    back to the same doubles); the appended columns as an array."""
    src = tmp_path / "angles.csv"
    with open(src, "w", newline="") as f:
        if unit == "rad":
            f.write("# angles: rad\n")
        f.write("theta_i,phi_i,theta_r,phi_r\n")
        for row in zip(*angles):
            f.write(",".join(repr(float(v)) for v in row) + "\n")
    out = tmp_path / "out.csv"
    run_cli(cli, "eval", "--params", params, "--input", src, "--output", out, *options)
    with open(out) as f:
        rows = [r for r in csv.reader(l for l in f if not l.startswith("#"))]
    header, body = rows[0], rows[1:]
    return np.array([[float(v) for v in r[4:]] for r in body]), header[4:]


def assert_bits(a, b):
    assert a.shape == b.shape
    assert a.dtype == np.float64 and b.dtype == np.float64
    same = a.view(np.uint64) == b.view(np.uint64)
    assert same.all(), f"{(~same).sum()} values differ, first at {np.argwhere(~same)[0]}"


def test_marschner_cubic_bit_identical_across_chunks(cli, tmp_path):
    # Past one 16384-row chunk, not a multiple of the 256-row batch.
    angles = random_angles(16384 + 3 * 256 + 37)
    expected, columns = cli_eval(cli, tmp_path, angles)
    got = hairfit.eval(PARAMS, *angles)
    assert_bits(got, expected)
    assert columns == hairfit.eval_columns(PARAMS) == ["s_0", "s_1", "s_2"]


def test_params_dict_path_and_fit_dir_agree(tmp_path):
    angles = random_angles(500, seed=3)
    from_path = hairfit.eval(PARAMS, *angles)
    params = json.loads(PARAMS.read_text())
    assert_bits(hairfit.eval(params, *angles), from_path)
    fit_dir = tmp_path / "fit"
    fit_dir.mkdir()
    (fit_dir / "params.json").write_text(PARAMS.read_text())
    assert_bits(hairfit.eval(fit_dir, *angles), from_path)
    # A directory that holds no fit is refused with the CLI's message (the library's).
    with pytest.raises(hairfit.HairfitError, match="is a directory without a params.json"):
        hairfit.eval(tmp_path, *angles)


def test_marschner_options_and_radians(cli, tmp_path):
    angles = random_angles(700, seed=11)
    opts = ("--mode", "exact", "--lobes", "R,TRT", "--no-glints")
    expected, _ = cli_eval(cli, tmp_path, angles, *opts)
    got = hairfit.eval(PARAMS, *angles, mode="exact", lobes="R,TRT", no_glints=True)
    assert_bits(got, expected)
    rad = [np.deg2rad(a) for a in angles]
    expected, _ = cli_eval(cli, tmp_path, rad, unit="rad")
    assert_bits(hairfit.eval(PARAMS, *rad, angles="rad"), expected)


def test_chiang_bit_identical(cli, tmp_path):
    angles = random_angles(300, seed=5)
    params = tmp_path / "chiang.json"
    params.write_text(json.dumps(CHIANG))
    expected, _ = cli_eval(cli, tmp_path, angles, "--model", "chiang", "--width-nodes", "64",
                           params=params)
    got = hairfit.eval(CHIANG, *angles, model="chiang", width_nodes=64)
    assert_bits(got, expected)


def test_bad_angles_name_the_array_and_index():
    with pytest.raises(hairfit.HairfitError, match=r"theta_r\[1\] = 90 degrees lies on the fiber axis"):
        hairfit.eval(PARAMS, [10, 10], [0, 0], [5, 90], [0, 0])
    with pytest.raises(hairfit.HairfitError, match="the same length"):
        hairfit.eval(PARAMS, [10, 10], [0], [5, 9], [0, 0])


def test_the_first_bad_angle_is_named_whatever_batch_it_is_in():
    # Bad values in several 256-sample batches (evaluated in parallel): the error names the
    # first one in sample order, as the sequential check did.
    ti, pi, tr, pr = (np.array(a) for a in random_angles(5000, seed=13))
    tr[4000] = 95.0
    pi[1300] = np.nan
    ti[2600] = -np.inf
    with pytest.raises(hairfit.HairfitError, match=r"^phi_i\[1300\] = NaN is not finite$"):
        hairfit.eval(PARAMS, ti, pi, tr, pr)
    pi[1300] = 721.0
    with pytest.raises(hairfit.HairfitError, match=r"^phi_i\[1300\] = 721 degrees is more than two turns"):
        hairfit.eval(PARAMS, ti, pi, tr, pr)
    pi[1300] = 720.0  # the bound itself is allowed
    with pytest.raises(hairfit.HairfitError, match=r"^theta_i\[2600\] = -inf is not finite$"):
        hairfit.eval(PARAMS, ti, pi, tr, pr)


def test_strided_arrays_give_the_same_bits():
    # hairfit.eval passes contiguous arrays (read in place); the native function copies others.
    angles = random_angles(3000, seed=17)
    flat = hairfit.eval(PARAMS, *angles)
    wide = [np.repeat(a, 2) for a in angles]
    strided = [w[::2] for w in wide]
    assert not strided[0].flags.c_contiguous
    got = hairfit._native.eval(None, str(PARAMS), *strided, ["--model", "marschner"], "deg")
    assert_bits(got, flat)
    assert_bits(hairfit.eval(PARAMS, *strided), flat)


TABLE_FAMILIES = {
    "kajiya-kay": {"model": "kajiya-kay", "k_d": [0.25, 0.5, 0.75], "k_s": 1.0, "exponent": 50},
    "deon": {"model": "deon", "sigma_a": [0.54, 1.0, 1.5], "beta_r_deg": 7, "beta_n_deg": 15,
             "alpha_deg": -3},
    "karis": {"model": "karis", "base_color": [0.2, 0.45, 0.7], "roughness": 0.4,
              "specular": 0.6, "scatter": 0.1},
    "frostbite": {"model": "frostbite", "base_color": [0.15, 0.4, 0.75], "smoothness": 0.88,
                  "radial_smoothness": 0.65, "cuticle_angle_deg": 2.5},
}


@pytest.mark.parametrize("family", sorted(TABLE_FAMILIES))
def test_table_families_bit_identical(cli, tmp_path, family):
    """Every table family through Python is the CLI's eval, bit for bit."""
    params = TABLE_FAMILIES[family]
    path = tmp_path / f"{family}.json"
    path.write_text(json.dumps(params))
    angles = random_angles(200, seed=11)
    expected, _ = cli_eval(cli, tmp_path, angles, "--model", family, params=path)
    got = hairfit.eval(params, *angles, model=family)
    assert got.shape == (200, 3)
    assert_bits(got, expected)


def test_out_receives_the_same_bits_and_is_returned():
    angles = random_angles(5000, seed=23)
    fresh = hairfit.eval(PARAMS, *angles)
    buf = np.full((5000, 3), np.nan)
    got = hairfit.eval(PARAMS, *angles, out=buf)
    assert got is buf
    assert_bits(buf, fresh)
    # Re-used: every value is overwritten.
    buf[:] = -1.0
    hairfit.eval(PARAMS, *angles, out=buf)
    assert_bits(buf, fresh)
    # Chiang through the same path.
    c = hairfit.eval(CHIANG, *(a[:300] for a in angles), model="chiang")
    cbuf = np.empty((300, 3))
    assert_bits(hairfit.eval(CHIANG, *(a[:300] for a in angles), model="chiang", out=cbuf), c)


def test_a_wrong_out_is_refused_naming_what_to_pass():
    angles = random_angles(100, seed=5)
    with pytest.raises(hairfit.HairfitError, match=r"out has shape \[100, 1\]; eval writes 100 samples × 3 channels: pass a C-contiguous np.empty\(\(100, 3\)\)"):
        hairfit.eval(PARAMS, *angles, out=np.empty((100, 1)))
    with pytest.raises(hairfit.HairfitError, match=r"not C-contiguous"):
        hairfit.eval(PARAMS, *angles, out=np.empty((3, 100)).T)
    with pytest.raises(hairfit.HairfitError, match=r"out must be a 2-D float64 NumPy array"):
        hairfit.eval(PARAMS, *angles, out=np.empty((100, 3), dtype=np.float32))
    with pytest.raises(hairfit.HairfitError, match=r"out must be a 2-D float64 NumPy array"):
        hairfit.eval(PARAMS, *angles, out=[[0.0] * 3] * 100)
    frozen = np.empty((100, 3))
    frozen.flags.writeable = False
    with pytest.raises(hairfit.HairfitError, match=r"out cannot be written"):
        hairfit.eval(PARAMS, *angles, out=frozen)
    # An out that shares memory with an angle array would overwrite angles not yet read.
    mem = np.empty(300)
    mem[:100] = angles[0]
    with pytest.raises(hairfit.HairfitError, match=r"out cannot be written"):
        hairfit.eval(PARAMS, mem[:100], *angles[1:], out=mem.reshape(100, 3))
