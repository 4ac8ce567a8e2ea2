//! `cutlab force` and `cutlab scenarios`, driven in-process.
#![cfg(feature = "cli")]
// Helpers outside #[test] functions unwrap too: a failed parse is a failed test.
#![allow(clippy::unwrap_used)]

mod common;
use cutlab::plant::Preset;

fn cutlab(args: &[&str]) -> (Result<(), String>, String) {
    common::cutlab_text(args, "")
}

fn json(args: &[&str]) -> serde_json::Value {
    let (result, out) = cutlab(args);
    assert!(result.is_ok(), "{result:?}");
    serde_json::from_str(&out).unwrap()
}

const SLOT: &[&str] = &[
    "force",
    "--diameter-mm",
    "20",
    "--teeth",
    "2",
    "--helix-deg",
    "30",
    "--axial-depth-mm",
    "3",
    "--radial-width-mm",
    "20",
    "--mode",
    "slot",
    "--feed-per-tooth-mm",
    "0.1",
    "--rpm",
    "1000",
];

#[test]
fn force_prints_simulated_means_that_equal_the_closed_form() {
    let mut args = SLOT.to_vec();
    args.extend(["--material", "sm45c"]);
    let v = json(&args);
    for key in [
        "mean_fx_n",
        "mean_fy_n",
        "mean_fz_n",
        "mean_torque_nm",
        "mean_power_w",
    ] {
        let got = v[key].as_f64().unwrap();
        let want = v["closed_form"][key].as_f64().unwrap();
        assert!(
            (got - want).abs() < 1e-3 * want.abs(),
            "{key}: {got} vs {want}"
        );
    }
    // tests/reference/plant/mean_forces.csv, first row (the same cut).
    assert!((v["mean_fy_n"].as_f64().unwrap() - 396.845).abs() < 0.4);
    let peak = v["peak_resultant_n"].as_f64().unwrap();
    assert!(peak > v["mean_resultant_n"].as_f64().unwrap());
    assert_eq!(v["feed_mm_min"].as_f64().unwrap(), 200.0);
    let power = v["mean_power_w"].as_f64().unwrap();
    let torque = v["mean_torque_nm"].as_f64().unwrap();
    assert!((power - torque * 1000.0 * std::f64::consts::TAU / 60.0).abs() < 1e-9);
}

#[test]
fn force_takes_explicit_coefficients() {
    let mut args = SLOT.to_vec();
    args.extend([
        "--ktc", "2200", "--krc", "790", "--kac", "440", "--kte", "35", "--kre", "45", "--kae", "3",
    ]);
    let explicit = json(&args);
    let mut args = SLOT.to_vec();
    args.extend(["--material", "sm45c"]);
    let named = json(&args);
    assert_eq!(explicit["mean_fx_n"], named["mean_fx_n"]);
    assert!(explicit["material"].is_null());
}

#[test]
fn force_errors_are_one_line_and_name_the_option() {
    // SLOT with `extra`'s options: a value for an option SLOT has replaces SLOT's (an option
    // given twice is an error of its own).
    let with = |extra: &[&'static str]| {
        let mut args = SLOT.to_vec();
        let mut rest = extra.iter().copied();
        while let Some(arg) = rest.next() {
            match args.iter().position(|a| *a == arg) {
                Some(i) => args[i + 1] = rest.next().unwrap(),
                None => args.push(arg),
            }
        }
        cutlab(&args).0.unwrap_err()
    };
    let cases: &[(&[&str], &str)] = &[
        (&["--material", "brass"], "--material"),
        (&["--material", "composite"], "--material"),
        (
            &["--material", "sm45c", "--ktc", "1"],
            "--material and --ktc",
        ),
        (&["--ktc", "2200"], "--krc"),
        (&["--material", "sm45c", "--mode", "sideways"], "--mode"),
        (&["--material", "sm45c", "--rpm", "-5"], "--rpm"),
        (&["--material", "sm45c", "--teeth", "40"], "--teeth"),
        (&["--material", "sm45c", "--helix-deg", "80"], "--helix-deg"),
        (
            &["--material", "sm45c", "--axial-depth-mm", "abc"],
            "--axial-depth-mm",
        ),
        (
            &["--material", "sm45c", "--runout-um", "5000"],
            "--runout-um",
        ),
        (
            &[
                "--material",
                "sm45c",
                "--helix-deg",
                "60",
                "--axial-depth-mm",
                "1e6",
            ],
            "--axial-depth-mm: 1000000 mm is deeper than",
        ),
    ];
    for (extra, option) in cases {
        let e = with(extra);
        assert!(e.contains(option), "{extra:?}: {e}");
        assert!(!e.contains("given twice"), "{e}");
        assert!(!e.contains('\n'), "{e}");
    }
    let (result, _) = cutlab(&["force", "--teeth", "2"]);
    assert_eq!(result.unwrap_err(), "missing required option --diameter-mm");
}

/// A slot's radial width is the diameter and no cut is wider than the cutter: a width that says
/// otherwise was read as full immersion without a word.
#[test]
fn force_refuses_a_radial_width_the_cut_would_not_use() {
    let with = |changes: &[(&'static str, &'static str)]| {
        let mut args: Vec<&str> = SLOT.to_vec();
        args.extend(["--material", "sm45c"]);
        for (option, value) in changes {
            let i = args.iter().position(|a| a == option).unwrap();
            args[i + 1] = value;
        }
        cutlab(&args)
    };
    let e = with(&[("--radial-width-mm", "3")]).0.unwrap_err();
    assert_eq!(
        e,
        "--radial-width-mm: a slot's radial width is the cutter's diameter (20 mm), not 3 mm; \
         leave --radial-width-mm out for a slot, or give --mode up or down for a cut 3 mm wide"
    );
    let e = with(&[("--radial-width-mm", "30"), ("--mode", "down")])
        .0
        .unwrap_err();
    assert_eq!(
        e,
        "--radial-width-mm: 30 mm is wider than the 20 mm cutter; the widest cut is the full \
         diameter (--mode slot)"
    );
    // The width a slot has, or any width up to the diameter in up or down milling, runs.
    let slot = json(
        &SLOT
            .iter()
            .copied()
            .chain(["--material", "sm45c"])
            .collect::<Vec<_>>(),
    );
    assert_eq!(slot["radial_width_mm"].as_f64(), Some(20.0));
    let (result, out) = with(&[("--radial-width-mm", "3"), ("--mode", "up")]);
    result.unwrap();
    let up: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(
        (up["radial_width_mm"].as_f64().unwrap() - 3.0).abs() < 1e-9,
        "{up}"
    );
    let mut without: Vec<&str> = SLOT.to_vec();
    let i = without
        .iter()
        .position(|a| *a == "--radial-width-mm")
        .unwrap();
    without.drain(i..i + 2);
    without.extend(["--material", "sm45c"]);
    assert_eq!(json(&without)["radial_width_mm"].as_f64(), Some(20.0));
}

#[test]
fn scenarios_lists_every_preset_with_its_source() {
    let (result, table) = cutlab(&["scenarios"]);
    assert!(result.is_ok());
    for p in Preset::ALL {
        assert!(
            table.contains(p.name()) && table.contains(p.source()),
            "{}",
            p.name()
        );
    }
    let v = json(&["scenarios", "--json"]);
    let list = v.as_array().unwrap();
    assert_eq!(list.len(), Preset::ALL.len());
    for item in list {
        assert!(item["source"].as_str().unwrap().starts_with("paper 00"));
        assert!(item["nominal_duration_s"].as_f64().unwrap() > 0.0);
        assert!(!item["choices"].as_array().unwrap().is_empty());
    }
    assert_eq!(list[0]["spindle_rpm"].as_f64(), Some(1000.0));
}

#[test]
fn every_preset_runs_from_the_cli() {
    for p in Preset::ALL {
        let (result, csv) = cutlab(&[
            "scenarios",
            "--run",
            p.name(),
            "--max-s",
            "0.05",
            "--every",
            "100",
        ]);
        assert!(result.is_ok(), "{}: {result:?}", p.name());
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 1 + 5, "{}: header and five rows", p.name());
        assert!(lines[0].starts_with("time [s],"));
        let v = json(&[
            "scenarios",
            "--run",
            p.name(),
            "--max-s",
            "0.05",
            "--summary",
            "--seed",
            "3",
        ]);
        assert_eq!(v["samples"].as_u64(), Some(500));
        assert_eq!(v["preset"].as_str(), Some(p.name()));
    }
}

#[test]
fn scenarios_errors_name_the_option() {
    let (result, _) = cutlab(&["scenarios", "--run", "nope"]);
    let e = result.unwrap_err();
    assert!(
        e.starts_with("--run: unknown preset \"nope\"") && e.contains("kim-step-doc"),
        "{e}"
    );
    let (result, _) = cutlab(&["scenarios", "--run", "kim-step-doc", "--override", "300"]);
    assert!(result.unwrap_err().starts_with("--override"));
    let (result, _) = cutlab(&["scenarios", "--seed", "3"]);
    assert_eq!(result.unwrap_err(), "--seed only applies with --run NAME");
}

/// An open-loop run that names no seed takes every run's (`cutlab sim`, `tune`, the browser's
/// form): one definition, which docs/plant.md's open-loop figures are computed with.
#[test]
fn scenarios_run_takes_every_runs_default_seed() {
    use cutlab::closed_loop::definition::DEFAULT_SEED;
    let args = [
        "scenarios",
        "--run",
        "kim-step-doc",
        "--max-s",
        "0.2",
        "--summary",
    ];
    let unseeded = json(&args);
    assert_eq!(unseeded["seed"].as_u64(), Some(DEFAULT_SEED));
    let seed = DEFAULT_SEED.to_string();
    let seeded = json(&[&args[..], &["--seed", seed.as_str()]].concat());
    assert_eq!(unseeded, seeded);
    let (result, help) = cutlab(&["scenarios", "--help"]);
    result.unwrap();
    assert!(
        help.contains(&format!("(default {DEFAULT_SEED}, as every run's)")),
        "{help}"
    );
}

/// A cut no end mill makes, or forces beyond f64, are refused naming the option: they once came
/// out as nulls (or absurd numbers) with exit 0.
#[test]
fn force_refuses_absurd_cuts_and_overflow() {
    let with = |changes: &[(&str, &str)]| {
        let mut args: Vec<&str> = SLOT.to_vec();
        if !changes.iter().any(|(o, _)| *o == "--ktc") {
            args.extend(["--material", "sm45c"]);
        } else {
            args.extend(["--krc", "790", "--kac", "440", "--kte", "35", "--kre", "45"]);
            args.extend(["--kae", "3"]);
        }
        for (option, value) in changes {
            match args.iter().position(|a| a == option) {
                Some(i) => args[i + 1] = value,
                None => args.extend([*option, *value]),
            }
        }
        cutlab(&args).0
    };
    let cases: [(&[(&str, &str)], &str); 7] = [
        (
            &[("--diameter-mm", "1e6")],
            "--diameter-mm: 1000000 mm is larger than any end mill",
        ),
        // Numbers in messages read as a person writes them, not as 300 digits.
        (
            &[("--axial-depth-mm", "1e300")],
            "--axial-depth-mm: 1e300 mm is deeper than a 20 mm cutter with a 30° helix",
        ),
        (
            &[("--feed-per-tooth-mm", "1e308")],
            "--feed-per-tooth-mm: 1e308 mm is beyond any feed per tooth",
        ),
        // A spindle speed no mill has: was accepted, with a feed of 4e299 mm/min.
        (
            &[("--rpm", "1e300")],
            "--rpm: 1e300 rev/min is beyond any milling spindle",
        ),
        (
            &[
                ("--diameter-mm", "10"),
                ("--radial-width-mm", "10"),
                ("--axial-depth-mm", "1000"),
            ],
            "--axial-depth-mm: 1000 mm is deeper than the flute",
        ),
        (&[("--feed-per-tooth-mm", "1e300")], "--feed-per-tooth-mm: "),
        (&[("--ktc", "1e308")], "the forces overflow f64"),
    ];
    for (changes, expected) in cases {
        let e = with(changes).unwrap_err();
        assert!(e.starts_with(expected), "{changes:?}: {e}");
    }
}

#[test]
fn learn_fits_paper_004s_network_on_a_presets_trial_cuts_and_refuses_what_it_cannot() {
    use cutlab::closed_loop::trial_cuts::preset_trial_cuts;
    use cutlab::estimation::power_law_fit::learn;
    use cutlab::plant::power_law::PowerLawReading;

    let v = json(&[
        "learn",
        "--scenario",
        "kim-step-doc",
        "--feeds-pct",
        "70,100",
        "--json",
    ]);
    // The same cuts and fit as the library's, so the command adds nothing of its own.
    let cuts = preset_trial_cuts(Preset::KimStepDoc, &[70.0, 100.0])
        .unwrap()
        .unwrap();
    let from_force = learn(&cuts.measured, PowerLawReading::USED, cuts.material).unwrap();
    assert_eq!(v["cuts"].as_array().unwrap().len(), 10);
    let feed = v["from_force"]["learned"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["input"] == "feed-per-tooth")
        .unwrap();
    let expected = from_force.learned[0].exponent;
    assert!((feed["exponent"].as_f64().unwrap() - expected).abs() < 1e-12);
    assert_eq!(
        v["from_estimate"]["residuals_pct"]
            .as_array()
            .unwrap()
            .len(),
        10
    );

    let (text, out) = cutlab(&[
        "learn",
        "--scenario",
        "kim-step-doc",
        "--feeds-pct",
        "80,100",
    ]);
    assert!(text.is_ok(), "{text:?}");
    for words in [
        "from the force",
        "from the estimate",
        "published",
        "mechanistic",
        "residual",
    ] {
        assert!(out.contains(words), "{words:?} in\n{out}");
    }

    for (args, message) in [
        (
            vec!["learn", "--scenario", "liu-current-step"],
            "liu-current-step has no cutter",
        ),
        (
            vec!["learn", "--scenario", "kim-step-doc", "--feeds-pct", "5"],
            "--feeds-pct: 5 % is outside 10–255 %",
        ),
        (
            vec!["learn", "--scenario", "kim-step-doc", "--feeds-pct", "80,x"],
            "--feeds-pct:",
        ),
        (vec!["learn", "--scenario", "nowhere"], "unknown preset"),
        (
            // One depth at three feeds: four cuts are needed for the feed's exponent and the bias.
            vec!["learn", "--scenario", "maneerat-doc-2"],
            "give at least 4 (each feed of --feeds-pct cuts every depth of the program once",
        ),
        (vec!["learn"], "--scenario"),
    ] {
        let (result, _) = cutlab(&args);
        let error = result.unwrap_err();
        assert!(error.contains(message), "{args:?}: {error}");
    }
}

/// A shop's own trial cuts as a table (`learn --cuts`): the table `--write-cuts` writes of a
/// preset's cuts learns what the preset's learning learns from the same forces, bit for bit;
/// a damaged table's rows are left out by line, never silently, and what cannot be read is
/// refused with the reason.
#[test]
fn learn_from_a_table_of_your_own_cuts_learns_what_the_lab_learns_and_names_every_row_left_out() {
    use cutlab::closed_loop::trial_cuts::learn_on_preset;
    let dir = std::env::temp_dir().join(format!("cutlab-learn-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let table = dir.join("cuts.csv");
    let table = table.to_str().unwrap();
    let (written, _) = cutlab(&[
        "learn",
        "--scenario",
        "kim-step-doc",
        "--feeds-pct",
        "70,100",
        "--write-cuts",
        table,
    ]);
    written.unwrap();
    let preset = learn_on_preset(Preset::KimStepDoc, &[70.0, 100.0]).unwrap();
    for (force_column, expected) in [
        (None, &preset.from_estimate),
        (Some("dynamometer force [N]"), &preset.from_force),
    ] {
        let mut args = vec!["learn", "--cuts", table, "--json"];
        if let Some(column) = force_column {
            args.extend(["--force-column", column]);
        }
        let v = json(&args);
        assert_eq!(v["lines"].as_array().unwrap().len(), 10);
        assert!(v["left_out"].as_array().unwrap().is_empty());
        for (got, want) in v["learned"]["learned"]
            .as_array()
            .unwrap()
            .iter()
            .zip(&expected.learned)
        {
            assert_eq!(
                got["exponent"].as_f64().unwrap(),
                want.exponent,
                "{force_column:?}"
            );
        }
        assert_eq!(v["learned"]["bias_n"].as_f64().unwrap(), expected.bias_n);
    }

    // A table from another shop: semicolons and decimal commas, its own names, the tool given
    // once, a row with a gap and one with a negative force.
    let messy = dir.join("messy.csv");
    let mut text = String::from("Width of cut (mm);FZ [mm];ap;Force [N]\n");
    for (i, a_e) in [4.0, 5.0, 6.0].iter().enumerate() {
        for (j, f) in [0.08, 0.1, 0.12].iter().enumerate() {
            let depth = 1.0 + ((i + 2 * j) % 3) as f64;
            let force = 600.0 * f64::powf(*a_e, 0.8) * f64::powf(*f, 0.7) * depth;
            text.push_str(&format!("{a_e};{f};{depth};{force:.6}\n").replace('.', ","));
        }
    }
    text.push_str("5;0,1;;300\n6;0,1;2;-3\n");
    std::fs::write(&messy, &text).unwrap();
    let messy = messy.to_str().unwrap();
    let (result, out) = cutlab(&[
        "learn",
        "--cuts",
        messy,
        "--diameter-mm",
        "20",
        "--teeth",
        "2",
    ]);
    result.unwrap();
    assert!(
        out.contains("9 trial cuts (2 rows left out, above)"),
        "{out}"
    );
    assert!(
        out.contains("note: line 11, ap: the depth of cut a_p is missing"),
        "{out}"
    );
    assert!(
        out.contains("note: line 12, Force [N]: the force is -3"),
        "{out}"
    );
    assert!(
        out.contains("0.70 ± 0.00"),
        "the feed's exponent 0.7 in\n{out}"
    );
    assert!(
        out.contains("0.80 ± 0.00"),
        "the width's exponent 0.8 in\n{out}"
    );
    // Width and feed stepped together cannot be told apart: said in the cuts' terms.
    let collinear = dir.join("collinear.csv");
    std::fs::write(
        &collinear,
        "a_e,f_z,a_p,d,z,force\n4,0.08,1,20,2,100\n5,0.1,2,20,2,220\n6,0.12,3,20,2,400\n\
         4,0.08,2,20,2,190\n5,0.1,3,20,2,330\n6,0.12,1,20,2,140\n4,0.08,3,20,2,280\n",
    )
    .unwrap();
    let (result, _) = cutlab(&["learn", "--cuts", collinear.to_str().unwrap()]);
    let error = result.unwrap_err();
    assert!(
        error.contains("vary width, feed per tooth and depth apart"),
        "{error}"
    );

    for (args, message) in [
        (
            vec!["learn", "--cuts", messy],
            "no column for the tool diameter d",
        ),
        (
            vec![
                "learn",
                "--cuts",
                messy,
                "--diameter-mm",
                "20",
                "--teeth",
                "2",
                "--material",
                "brass",
            ],
            "--material: no material \"brass\"",
        ),
        (
            vec!["learn", "--cuts", messy, "--scenario", "kim-step-doc"],
            "leave out --scenario",
        ),
        (
            vec!["learn", "--scenario", "kim-step-doc", "--teeth", "2"],
            "--teeth goes with --cuts",
        ),
        (
            vec!["learn", "--cuts", table, "--force-column", "F"],
            "the force column \"F\" is not in the table",
        ),
    ] {
        let (result, _) = cutlab(&args);
        let error = result.unwrap_err();
        assert!(error.contains(message), "{args:?}: {error}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
