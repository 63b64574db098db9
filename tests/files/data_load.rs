//! The loader on well-formed files of each format: exact accounting of every row, each
//! rejection reason, fixed-angle scan mapping, and write→load round trips.

use crate::support::cli;

use cli::write;
use std::path::{Path, PathBuf};

use proptest::prelude::*;

use hairfit::data::{
    load, round_trip_degrees, write_csv, write_json, AngleUnit, Dataset, Format, LoadOptions,
    LoadReport, RejectReason::*,
};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/loader")
        .join(name)
}

fn scan_options(columns: &str, fixed: &str, maps: &[&str]) -> LoadOptions {
    LoadOptions {
        columns: columns.split(',').map(String::from).collect(),
        fixed: fixed
            .split(',')
            .filter(|s| !s.is_empty())
            .map(String::from)
            .collect(),
        maps: maps.iter().map(|s| s.to_string()).collect(),
        ..LoadOptions::default()
    }
}

/// The accounting invariant every report must satisfy.
fn assert_accounts(report: &LoadReport, ds: &Dataset) {
    assert_eq!(report.rows_read, report.accepted + report.rejected_total());
    assert_eq!(report.accepted as usize, ds.len());
    assert_eq!(ds.source_line.len(), ds.len());
    assert_eq!(ds.radiance.len(), ds.len() * ds.n_channels());
}

#[test]
fn messy_csv_counts_every_reason_exactly() {
    let (ds, r) = load(&fixture("messy.csv"), &LoadOptions::default()).unwrap();
    assert_accounts(&r, &ds);
    assert_eq!(r.format, "csv");
    assert_eq!(r.rows_read, 14);
    assert_eq!(r.accepted, 4);
    assert_eq!(r.rejected_count(MissingValue), 2);
    assert_eq!(r.rejected[&MissingValue].first_lines, [4, 5]);
    assert_eq!(r.rejected_count(NonFinite), 3);
    assert_eq!(r.rejected[&NonFinite].first_lines, [7, 8, 9]);
    assert_eq!(r.rejected_count(ThetaOutOfRange), 2);
    assert_eq!(r.rejected[&ThetaOutOfRange].first_lines, [10, 11]);
    assert_eq!(r.rejected_count(NonPositiveSigma), 2);
    assert_eq!(r.rejected[&NonPositiveSigma].first_lines, [13, 14]);
    assert_eq!(r.rejected_count(Duplicate), 1);
    assert_eq!(r.duplicate_of, [[15, 3]]);
    assert_eq!(r.rejected_count(NegativeRadiance), 0);
    assert_eq!(r.negative_kept.count, 2);
    assert_eq!(r.negative_kept.first_lines, [12, 18]);
    assert!(r
        .notes
        .iter()
        .any(|n| n.contains("ignored columns: operator")));
    assert_eq!(ds.source_line, [3, 12, 17, 18]);
    assert_eq!(ds.channels, ["radiance"]);
    // 1e308 is finite and kept as is.
    assert_eq!(ds.value(2, 0), 1e308);
    assert_eq!(ds.sigma.as_deref(), Some(&[0.1; 4][..]));
    // Degrees are converted with f64::to_radians, so the same call gives the same bits.
    assert_eq!(ds.angles(0), [10f64, 0.0, 20.0, 30.0].map(f64::to_radians));
    let text = r.to_string();
    assert!(
        text.contains("14 rows read, 4 accepted, 10 rejected"),
        "{text}"
    );
    assert!(text.contains("line 15 repeats line 3"), "{text}");
}

#[test]
fn negative_tolerance_rejects_only_beyond_it() {
    let options = LoadOptions {
        negative_tolerance: Some(0.001),
        ..LoadOptions::default()
    };
    let (ds, r) = load(&fixture("messy.csv"), &options).unwrap();
    assert_accounts(&r, &ds);
    assert_eq!(r.rejected_count(NegativeRadiance), 1);
    assert_eq!(r.rejected[&NegativeRadiance].first_lines, [12]);
    assert_eq!(r.accepted, 3);
    assert_eq!(r.negative_kept.first_lines, [18]);
}

#[test]
fn report_serializes_with_reason_names() {
    let (_, r) = load(&fixture("messy.csv"), &LoadOptions::default()).unwrap();
    let v = serde_json::to_value(&r).unwrap();
    assert_eq!(v["rows_read"], 14);
    assert_eq!(v["rejected"]["non_finite"]["count"], 3);
    assert_eq!(v["rejected"]["duplicate"]["first_lines"][0], 15);
    assert_eq!(v["negative_kept"]["count"], 2);
}

#[test]
fn multichannel_csv_broadcasts_sigma_and_reads_weights() {
    let (ds, r) = load(&fixture("rgb.csv"), &LoadOptions::default()).unwrap();
    assert_accounts(&r, &ds);
    assert_eq!(ds.channels, ["r", "g", "b"]);
    assert_eq!(r.rows_read, 3);
    assert_eq!(r.rejected_count(NonPositiveWeight), 1);
    assert_eq!(r.rejected[&NonPositiveWeight].first_lines, [3]);
    assert_eq!(ds.len(), 2);
    assert_eq!(ds.value(1, 2), 9.0);
    assert_eq!(
        ds.sigma.as_deref(),
        Some(&[0.5, 0.5, 0.5, 0.25, 0.25, 0.25][..])
    );
    assert_eq!(
        ds.weight.as_deref(),
        Some(&[1.0, 1.0, 2.0, 1.0, 3.0, 1.0][..])
    );
    assert_eq!(ds.weight_of(1, 1), Some(3.0));
}

#[test]
fn radians_option_skips_conversion_and_uses_the_radian_limit() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "rad.csv",
        "theta_i,phi_i,theta_r,phi_r,radiance\n0.5,0,1.5,3,1\n0.5,0,1.5708,3,1\n",
    );
    let options = LoadOptions {
        angles: Some(AngleUnit::Rad),
        ..LoadOptions::default()
    };
    let (ds, r) = load(&p, &options).unwrap();
    assert_eq!(ds.angles(0), [0.5, 0.0, 1.5, 3.0]);
    // 1.5708 > π/2 = 1.57079...: on the axis side of the limit.
    assert_eq!(r.rejected_count(ThetaOutOfRange), 1);
    // The same file read as degrees keeps both rows.
    let (_, r) = load(&p, &LoadOptions::default()).unwrap();
    assert_eq!(r.accepted, 2);
}

#[test]
fn unit_directive_is_honoured_and_conflicts_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "d.csv",
        "# angles: rad\ntheta_i,phi_i,theta_r,phi_r,radiance\n0.5,0,1,3,1\n",
    );
    let (ds, _) = load(&p, &LoadOptions::default()).unwrap();
    assert_eq!(ds.angles(0), [0.5, 0.0, 1.0, 3.0]);
    let options = LoadOptions {
        angles: Some(AngleUnit::Deg),
        ..LoadOptions::default()
    };
    let msg = load(&p, &options).unwrap_err().to_string();
    assert!(
        msg.contains("d.csv:1:1") && msg.contains("--angles"),
        "{msg}"
    );
}

#[test]
fn fixed_angle_scan_lands_values_in_the_right_fields() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "scan.txt",
        "# phi  polar  value\n10 60 1.25\n20\t60.5   ?\n\n30 -5 2\n40 61 -3\n",
    );
    let options = scan_options(
        "phi_r,theta_r,radiance",
        "theta_i=30,phi_i=0",
        &["theta_r=90-x"],
    );
    let (ds, r) = load(&p, &options).unwrap();
    assert_accounts(&r, &ds);
    assert_eq!(r.format, "scan");
    assert_eq!(r.rows_read, 4);
    assert_eq!(r.rejected_count(MissingValue), 1);
    assert_eq!(r.rejected[&MissingValue].first_lines, [3]);
    // polar -5 maps to θ_r = 95°: past the axis.
    assert_eq!(r.rejected[&ThetaOutOfRange].first_lines, [5]);
    assert_eq!(ds.source_line, [2, 6]);
    // The map is -1·x + 90, evaluated exactly for these integers, then to_radians.
    assert_eq!(ds.theta_r, [30f64.to_radians(), 29f64.to_radians()]);
    assert_eq!(ds.phi_r, [10f64.to_radians(), 40f64.to_radians()]);
    assert_eq!(ds.theta_i, [30f64.to_radians(); 2]);
    assert_eq!(ds.phi_i, [0.0; 2]);
    assert_eq!(ds.radiance, [1.25, -3.0]);
    assert_eq!(r.negative_kept.first_lines, [6]);
}

#[test]
fn scan_with_commas_skip_columns_radians_and_channels() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "scan.dat",
        "0.1, 99, 0.2, 1, 2, 0.5\n0.3, 99, 0.4, 3, 4, 0.5\n",
    );
    let mut options = scan_options(
        "theta_r,skip,phi_r,radiance_r,radiance_g,sigma",
        "theta_i=0.5,phi_i=-1",
        &["phi_r=2*x+1", "radiance_g=x/2"],
    );
    options.angles = Some(AngleUnit::Rad);
    let (ds, r) = load(&p, &options).unwrap();
    assert_accounts(&r, &ds);
    assert_eq!(ds.channels, ["r", "g"]);
    assert_eq!(ds.theta_i, [0.5, 0.5]);
    assert_eq!(ds.phi_i, [-1.0, -1.0]);
    assert_eq!(ds.theta_r, [0.1, 0.3]);
    // Same arithmetic as the map (2·x + 1), so equal bits.
    assert_eq!(ds.phi_r, [2.0 * 0.2 + 1.0, 2.0 * 0.4 + 1.0]);
    assert_eq!(ds.radiance, [1.0, 1.0, 3.0, 2.0]);
    assert_eq!(ds.sigma.as_deref(), Some(&[0.5; 4][..]));
}

#[test]
fn scan_option_errors_say_what_is_missing() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "s.txt", "1 2 3\n");
    let cases: [(LoadOptions, &str); 7] = [
        (
            scan_options("phi_r,theta_r,radiance", "theta_i=90,phi_i=0", &[]),
            "|theta| must be below 90",
        ),
        (
            scan_options("phi_r,theta_r,radiance", "theta_i=30", &[]),
            "phi_i",
        ),
        (
            scan_options(
                "phi_r,theta_r,radiance",
                "theta_i=30,phi_i=0",
                &["theta_r=x*x"],
            ),
            "not linear",
        ),
        (
            scan_options(
                "phi_r,theta_r,radiance",
                "theta_i=30,phi_i=0",
                &["theta_i=90-x"],
            ),
            "not one of the --columns",
        ),
        (
            scan_options("phi_r,theta_r,foo", "theta_i=30,phi_i=0", &[]),
            "unknown column name `foo`",
        ),
        (
            scan_options("phi_r,theta_r,phi_i", "theta_i=30", &[]),
            "radiance",
        ),
        (
            scan_options("phi_r,theta_r,radiance", "theta_i=30,phi_i=zero", &[]),
            "not a finite number",
        ),
    ];
    for (options, want) in cases {
        let msg = load(&p, &options).unwrap_err().to_string();
        assert!(msg.contains(want), "{want}: {msg}");
    }
    // A scan without --columns cannot be read.
    let msg = load(&p, &LoadOptions::default()).unwrap_err().to_string();
    assert!(msg.contains("--columns"), "{msg}");
}

#[test]
fn shipped_scan_example_loads_as_documented() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/scan_example.txt");
    let mut options = scan_options(
        "phi_r,theta_r,radiance",
        "theta_i=20,phi_i=0",
        &["theta_r=90-x"],
    );
    options.missing = "?".into();
    let (ds, r) = load(&path, &options).unwrap();
    assert_accounts(&r, &ds);
    assert_eq!((r.rows_read, r.accepted), (169, 167));
    assert_eq!(r.rejected[&MissingValue].first_lines, [152, 165]);
    assert_eq!((r.negative_kept.count, r.replicates.count), (0, 0));
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    // The polar column mapped through 90 − x: θ_r spans −72° … 72°.
    let theta_r: Vec<f64> = (0..ds.len()).map(|i| ds.angles_deg(i)[2]).collect();
    let max = theta_r.iter().cloned().fold(f64::MIN, f64::max);
    let min = theta_r.iter().cloned().fold(f64::MAX, f64::min);
    assert_eq!((min, max), (-72.0, 72.0));
}

#[test]
fn json_dataset_reports_rows_with_their_lines() {
    let (ds, r) = load(&fixture("dataset.json"), &LoadOptions::default()).unwrap();
    assert_accounts(&r, &ds);
    assert_eq!(r.format, "json");
    assert_eq!(r.rows_read, 6);
    assert_eq!(r.accepted, 2);
    assert_eq!(r.rejected[&MissingValue].first_lines, [6, 7]);
    assert_eq!(r.rejected[&ThetaOutOfRange].first_lines, [8]);
    assert_eq!(r.duplicate_of, [[9, 5]]);
    assert_eq!(r.negative_kept.first_lines, [10]);
    assert_eq!(ds.channels, ["r", "g"]);
    assert_eq!(ds.source_line, [5, 10]);
    assert_eq!(ds.radiance, [1.5, 2.5, -0.25, 4.0]);
    assert_eq!(ds.sigma.as_deref(), Some(&[0.1, 0.1, 0.1, 0.2][..]));
    assert_eq!(ds.meta["fiber"], "blond #3");
}

/// A dataset with awkward values: negative zero, subnormal-free extremes, several channels.
fn sample_dataset() -> Dataset {
    let mut ds = Dataset::with_channels(vec!["r".into(), "g".into()], true, true);
    let mut x = 0.123_456_789_f64;
    for i in 0..200u64 {
        // A deterministic scramble of values with full 53-bit mantissas.
        x = (x * 3.917_345_123 + 0.271_828_182_845).fract();
        let angles = [
            (x - 0.5) * 3.1,
            (x * 7.0).fract() * 6.2 - 3.1,
            (0.5 - (x * 13.0).fract()) * 3.1,
            if i == 0 {
                -0.0
            } else {
                (x * 17.0).fract() * 6.2 - 3.1
            },
        ];
        let radiance = [x * 1e-3 - 2e-4, 1.0 / (x + 1e-9)];
        ds.push(
            angles,
            &radiance,
            Some(&[x + 1e-3, 0.1]),
            Some(&[1.0, x + 0.5]),
            i + 1,
        );
    }
    ds.meta.insert("source".into(), "synthetic".into());
    ds
}

/// Distance in units in the last place between two finite f64 of the same sign.
fn ulps(a: f64, b: f64) -> u64 {
    assert_eq!(a.is_sign_negative(), b.is_sign_negative(), "{a} vs {b}");
    a.to_bits().abs_diff(b.to_bits())
}

#[test]
fn csv_write_then_load_keeps_values_exactly_and_radians_within_one_ulp() {
    let ds = sample_dataset();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("out.csv");
    write_csv(&ds, &p).unwrap();
    let (back, r) = load(&p, &LoadOptions::default()).unwrap();
    assert_eq!(r.accepted, 200);
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(back.channels, ds.channels);
    // Values are written in shortest round-trip form and parsed correctly rounded: bit-exact.
    for (a, b) in [
        (&back.radiance, &ds.radiance),
        (back.sigma.as_ref().unwrap(), ds.sigma.as_ref().unwrap()),
        (back.weight.as_ref().unwrap(), ds.weight.as_ref().unwrap()),
    ] {
        assert_eq!(bits(a), bits(b));
    }
    // These radians are arbitrary 53-bit values, not images of degrees. The file holds degrees
    // d with d.to_radians() as close as any f64 gets: to_radians multiplies by ~2^-6·1.117, so
    // the radian values it reaches are at most 2 ulp apart and a skipped one is 1 ulp from a
    // reached one. Hence 1 ulp, and exact for most (the -0.0 of sample 0 keeps its sign).
    let mut exact = 0;
    for i in 0..ds.len() {
        for (a, b) in back.angles(i).into_iter().zip(ds.angles(i)) {
            let d = ulps(a, b);
            assert!(d <= 1, "sample {i}: {a:?} vs {b:?} ({d} ulp)");
            exact += usize::from(d == 0);
        }
    }
    assert!(exact >= 600, "only {exact} of 800 angles exact");
    // Two comment lines and the header come first.
    assert_eq!(back.source_line[0], 4);
}

#[test]
fn csv_holds_degrees_and_angles_that_began_as_degrees_round_trip_exactly() {
    let mut ds = Dataset::with_channels(vec!["radiance".into()], false, false);
    let mut x = 0.413_217_5_f64;
    let mut degrees = vec![[15.0, 0.0, -15.0, -177.0], [-0.0, 179.5, 89.0, 1e-20]];
    for _ in 0..500 {
        // Full-mantissa degrees, like the sphere rig's asin(z).to_degrees().
        x = (x * 3.917_345_123 + 0.271_828_182_845).fract();
        degrees.push([
            (x - 0.5) * 178.0,
            (x * 7.0).fract() * 360.0 - 180.0,
            x,
            -x * 1e-3,
        ]);
    }
    for (k, d) in degrees.iter().enumerate() {
        ds.push(d.map(f64::to_radians), &[k as f64], None, None, 0);
    }
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("deg.csv");
    write_csv(&ds, &p).unwrap();
    let text = std::fs::read_to_string(&p).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("# written by hairfit; angles in degrees")
    );
    assert_eq!(lines.next(), Some("# angles: deg"));
    assert_eq!(lines.next(), Some("theta_i,phi_i,theta_r,phi_r,radiance"));
    // A person reads the degrees that were meant, not 15.000000000000002.
    assert_eq!(lines.next(), Some("15.0,0.0,-15.0,-177.0,0"));
    assert_eq!(lines.next(), Some("-0.0,179.5,89.0,1e-20,1"));
    let (back, _) = load(&p, &LoadOptions::default()).unwrap();
    for i in 0..ds.len() {
        let (a, b) = (back.angles(i), ds.angles(i));
        assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits), "sample {i}");
    }
    // --angles rad contradicts the file's own directive: an error, not a misreading.
    let rad = LoadOptions {
        angles: Some(AngleUnit::Rad),
        ..LoadOptions::default()
    };
    let msg = load(&p, &rad).unwrap_err().to_string();
    assert!(msg.contains("deg.csv:2:1"), "{msg}");
}

proptest! {
    // Cheap (a few multiplications per case), so many cases over every magnitude.
    #![proptest_config(ProptestConfig::with_cases(4000))]

    /// Degrees → radians → round_trip_degrees → radians is the identity, and the degrees
    /// written are never longer text than the ones that were meant.
    #[test]
    fn degrees_come_back_exactly(m in -1.0f64..1.0, e in -300i32..300) {
        let d = m * 10f64.powi(e);
        let r = d.to_radians();
        prop_assume!(r.is_normal());
        let w = round_trip_degrees(r);
        prop_assert_eq!(w.to_radians().to_bits(), r.to_bits(), "{:?} -> {:?}", d, w);
        prop_assert!(format!("{w:?}").len() <= format!("{d:?}").len(), "{:?} -> {:?}", d, w);
    }

    /// Any normal radian value comes back within 1 ulp (see the CSV round-trip test for why).
    #[test]
    fn arbitrary_radians_come_back_within_one_ulp(bits in any::<u64>()) {
        let r = f64::from_bits(bits);
        prop_assume!(r.is_normal() && r.to_degrees().is_finite());
        let back = round_trip_degrees(r).to_radians();
        prop_assert!(ulps(back, r) <= 1, "{:?} -> {:?}", r, back);
    }
}

#[test]
fn whole_degrees_are_written_as_themselves() {
    for k in -3600..=3600 {
        let d = f64::from(k) / 10.0;
        assert_eq!(round_trip_degrees(d.to_radians()), d, "{d}");
    }
}

#[test]
fn csv_files_in_radians_still_load() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "old.csv",
        "# written by hairfit; angles in radians\n# angles: rad\n\
         theta_i,phi_i,theta_r,phi_r,radiance\n0.2617993877991494,0,-0.2617993877991494,-3,1\n",
    );
    let (ds, _) = load(&p, &LoadOptions::default()).unwrap();
    assert_eq!(
        ds.angles(0),
        [0.2617993877991494, 0.0, -0.2617993877991494, -3.0]
    );
    assert_eq!(ds.source_line, [4]);
}

#[test]
fn json_write_then_load_round_trips() {
    let ds = sample_dataset();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("out.json");
    write_json(&ds, &p).unwrap();
    let (back, r) = load(&p, &LoadOptions::default()).unwrap();
    assert_eq!(r.accepted, 200);
    assert_eq!(back.channels, ds.channels);
    assert_eq!(back.meta, ds.meta);
    // One sample per line after the 4 header lines.
    assert_eq!(back.source_line[0], 5);
    assert_eq!(back.source_line[199], 204);
    // Angles are written as the degrees that map back nearest (as in the CSV test): the
    // decimal text round-trips exactly (serde_json's float_roundtrip parser), and the degrees
    // come back within 1 ulp of these arbitrary radians.
    for i in 0..ds.len() {
        for (a, b) in back.angles(i).into_iter().zip(ds.angles(i)) {
            assert!(ulps(a, b) <= 1, "sample {i}: {a:?} vs {b:?}");
        }
    }
    // Values are written in shortest round-trip form and parsed correctly rounded: bit-exact.
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&back.radiance), bits(&ds.radiance));
    assert_eq!(
        bits(back.sigma.as_ref().unwrap()),
        bits(ds.sigma.as_ref().unwrap())
    );
    assert_eq!(
        bits(back.weight.as_ref().unwrap()),
        bits(ds.weight.as_ref().unwrap())
    );
}

#[test]
fn format_is_detected_from_extension_and_overridable() {
    use hairfit::data::detect_format;
    let d = LoadOptions::default();
    assert_eq!(detect_format(Path::new("a.CSV"), &d), Format::Csv);
    assert_eq!(detect_format(Path::new("a.json"), &d), Format::Json);
    assert_eq!(detect_format(Path::new("a.txt"), &d), Format::Scan);
    let forced = LoadOptions {
        format: Some(Format::Csv),
        ..LoadOptions::default()
    };
    assert_eq!(detect_format(Path::new("a.txt"), &forced), Format::Csv);
    let scan = scan_options("phi_r,theta_r,radiance", "", &[]);
    assert_eq!(detect_format(Path::new("a.csv"), &scan), Format::Scan);
}

#[test]
fn duplicates_match_signed_zeros_and_wrapped_azimuths_and_keep_channels_aligned() {
    // Only identical lines are duplicates; the same direction with other values is a replicate.
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "dup.csv",
        "theta_i,phi_i,theta_r,phi_r,radiance_r,radiance_g,sigma_r,sigma_g\n\
         0,0,10,20,1,2,0.1,0.2\n\
         1,0,10,20,3,4,0.3,0.4\n\
         -0,0,10,20,1,2,0.1,0.2\n\
         0,-0,10,20,1,2,0.1,0.2\n\
         2,0,10,20,9,10,0.9,1.0\n\
         1,360,10,20,3,4,0.3,0.4\n\
         1,0,10,-340,5,6,0.5,0.6\n\
         1,0,10,20,3,4,0.3,0.5\n",
    );
    let (ds, r) = load(&p, &LoadOptions::default()).unwrap();
    assert_accounts(&r, &ds);
    assert_eq!(r.rejected[&Duplicate].first_lines, [4, 5, 7]);
    assert_eq!(r.duplicate_of, [[4, 2], [5, 2], [7, 3]]);
    assert_eq!(ds.source_line, [2, 3, 6, 8, 9]);
    // φ_r = −340° is 20° after wrapping; line 9 differs from line 3 in one sigma only.
    assert_eq!(r.replicates.count, 2);
    assert_eq!(r.replicates.first_lines, [8, 9]);
    assert_eq!(
        ds.radiance,
        [1.0, 2.0, 3.0, 4.0, 9.0, 10.0, 5.0, 6.0, 3.0, 4.0]
    );
    assert_eq!(
        ds.sigma.as_deref(),
        Some(&[0.1, 0.2, 0.3, 0.4, 0.9, 1.0, 0.5, 0.6, 0.3, 0.5][..])
    );
    let text = r.to_string();
    assert!(
        text.contains("replicates (a direction measured again, kept): 2"),
        "{text}"
    );
    // fit.json and `load --json` carry the count; an older report without it reads as 0.
    let v = serde_json::to_value(&r).unwrap();
    assert_eq!(v["replicates"]["count"], 2);
    let old: hairfit::data::LoadReport = serde_json::from_str(r#"{"rows_read": 3}"#).unwrap();
    assert_eq!(old.replicates.count, 0);
}

#[test]
fn repeated_measurements_of_one_direction_are_all_kept() {
    // Five readings at each of two directions, as a goniometer repeating a scan: all ten kept.
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::from("theta_i,phi_i,theta_r,phi_r,radiance\n");
    for k in 0..5 {
        text += &format!(
            "30,0,-30,{},{}\n",
            170 + 360 * (k % 2),
            1.0 + 0.01 * k as f64
        );
        text += &format!("30,0,-30,-10,{}\n", 2.0 + 0.01 * k as f64);
    }
    let p = write(dir.path(), "rep.csv", &text);
    let (ds, r) = load(&p, &LoadOptions::default()).unwrap();
    assert_accounts(&r, &ds);
    assert_eq!((r.accepted, r.rejected_total()), (10, 0));
    assert_eq!(r.replicates.count, 8, "two directions, four repeats each");
}
