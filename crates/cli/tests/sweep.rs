//! `lagrange sweep` end to end: the real binary on a small double-pendulum grid
//! (rows, shards merged back to the unsharded output, the heat map) and bad
//! grids (exit 2); an axis of listed values (`a=0;1;5`).

use crate::common::{ok, repo_root, run as lagrange, scratch};
use std::path::Path;

fn text(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

const GRID: &str = "a=-3:3:4,b=-3:3:4";

/// A lane takes the next run of its job as soon as its own ends. The whole
/// sweep of 48 runs on one thread runs jobs of 12 (three runs per lane pair
/// with the Lyapunov twin, one and a half per lane without), its shards of 8
/// runs jobs that fill the lanes once; both must give the same rows, bit for
/// bit, however the runs' lengths differ.
#[test]
fn lanes_that_take_the_next_run_give_the_rows_of_lanes_that_do_not() {
    let model = repo_root().join("examples/double_pendulum.toml");
    let model = model.to_str().unwrap();
    let grid = "a=-3:3:6,b=-3:3:8";
    for lyapunov in [true, false] {
        let run = |out: &std::path::Path, shard: Option<&str>| {
            let mut args =
                vec!["sweep", model, "--until", "3", "--grid", grid, "--threads", "1", "--out", out.to_str().unwrap()];
            if let Some(shard) = shard {
                args.extend(["--shard", shard]);
            }
            if !lyapunov {
                args.push("--no-lyapunov");
            }
            ok(&args);
        };
        let whole = scratch("sweep-test", &format!("refill-whole-{lyapunov}.csv"));
        run(&whole, None);
        let mut parts = Vec::new();
        for i in 0..6 {
            let part = scratch("sweep-test", &format!("refill-part{i}-{lyapunov}.csv"));
            run(&part, Some(&format!("{i}/6")));
            parts.push(part.to_str().unwrap().to_string());
        }
        let merged = scratch("sweep-test", &format!("refill-merged-{lyapunov}.csv"));
        let mut args = vec!["sweep", "--merge", merged.to_str().unwrap()];
        args.extend(parts.iter().map(String::as_str));
        ok(&args);
        let (whole, merged) = (text(&whole), text(&merged));
        assert_eq!(whole.lines().count(), 2 + 48);
        assert_eq!(merged, whole, "lyapunov: {lyapunov}");
    }
}

#[test]
fn shards_merge_to_the_whole_sweep_and_the_heat_map_is_drawn() {
    let model = repo_root().join("examples/double_pendulum.toml");
    let model = model.to_str().unwrap();
    let whole = scratch("sweep-test", "whole.csv");
    let svg = scratch("sweep-test", "map.svg");
    ok(&[
        "sweep",
        model,
        "--until",
        "2",
        "--grid",
        GRID,
        "--out",
        whole.to_str().unwrap(),
        "--heatmap",
        svg.to_str().unwrap(),
    ]);
    let csv = text(&whole);
    let lines: Vec<&str> = csv.lines().collect();
    assert!(
        lines[0].starts_with("# lagrange sweep; model=planar double pendulum; grid=a=-3.0:3.0:4,b=-3.0:3.0:4; runs=16")
    );
    assert_eq!(lines[1], "run,a,b,t_final,final_a,final_b,final_a',final_b',energy_drift,lyapunov,failure");
    assert_eq!(lines.len(), 2 + 16);
    for (k, line) in lines[2..].iter().enumerate() {
        let fields: Vec<&str> = line.split(',').collect();
        assert_eq!(fields[0], k.to_string());
        assert_eq!(fields[3], "2.0", "t_final of {line}");
        let drift: f64 = fields[8].parse().unwrap();
        assert!(drift < 1e-6, "{line}");
        assert!(fields[9].parse::<f64>().unwrap().is_finite() && fields[10].is_empty(), "{line}");
    }
    let map = text(&svg);
    assert!(map.contains("<svg") && map.contains("largest Lyapunov exponent"), "{}", &map[..200.min(map.len())]);

    let mut parts = Vec::new();
    for i in 0..3 {
        let part = scratch("sweep-test", &format!("part{i}.csv"));
        let shard = format!("{i}/3");
        ok(&[
            "sweep",
            model,
            "--until",
            "2",
            "--grid",
            GRID,
            "--shard",
            &shard,
            "--threads",
            "1",
            "--out",
            part.to_str().unwrap(),
        ]);
        parts.push(part.to_str().unwrap().to_string());
    }
    let merged = scratch("sweep-test", "merged.csv");
    let mut args = vec!["sweep", "--merge", merged.to_str().unwrap()];
    args.extend(parts.iter().rev().map(String::as_str));
    ok(&args);
    assert_eq!(text(&merged), csv);

    // Two of three shards: the merge names what is missing.
    let out = lagrange(&["sweep", "--merge", merged.to_str().unwrap(), &parts[0], &parts[2]]);
    assert_eq!(out.code, Some(2));
    let err = &out.stderr;
    assert!(err.contains("5 of 16 runs are missing (first: [1, 4, 7, 10, 13]); missing shards: 1/3"), "{err}");
}

#[test]
fn bad_grids_and_requests_exit_2() {
    let model = repo_root().join("examples/double_pendulum.toml");
    let model = model.to_str().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["--grid", "a=0:1"], "'a=0:1' is not NAME=START:STOP:COUNT (evenly spaced) or NAME=V1;V2;..."),
        (&["--grid", "a=0;x;1"], "the value of 'a' must be a finite number, not 'x'"),
        (
            &["--grid", "a=0;1;5,b=0:1:3", "--heatmap", "x.svg"],
            "the values of 'a' are not (give it as START:STOP:COUNT)",
        ),
        (
            &["--grid", "z=0:1:3"],
            "'z' is not a coordinate, a velocity or a parameter of the model (known: a, a', b, b'",
        ),
        (&["--grid", "a=0:1:0"], "the count of 'a' must be a whole number of at least 1, not '0'"),
        (&["--grid", "a=0:1:3", "--heatmap", "x.svg"], "--heatmap needs a 2-D grid"),
        (&["--grid", "a=0:1:3,b=0:1:3", "--heatmap", "x.svg", "--color", "c"], "--color 'c' is not available"),
        (&["--grid", "a=0:1:3", "--shard", "3/3"], "--shard must be I/N"),
        // A map's cells are held while the rows stream: at most 10^6, refused before any run.
        (&["--grid", "a=0:1:2000,b=0:1:1000", "--heatmap", "x.svg"], "--heatmap draws at most 1000000 cells"),
        (&["--grid", "a=0:1:3,b=0:1:3", "--heatmap", "x.svg", "--no-lyapunov"], "--color 'lyapunov' is not available"),
    ];
    for (extra, expect) in cases {
        let mut args = vec!["sweep", model, "--until", "1"];
        args.extend_from_slice(extra);
        let out = lagrange(&args);
        let err = &out.stderr;
        assert_eq!(out.code, Some(2), "{extra:?}: {err}");
        assert!(err.contains(expect), "{extra:?}: {err}");
    }
}

/// Runs whose series is not finite fail alone: x'' = −(3/2)·sqrt(x) has no
/// real rate below x = 0 and an infinite one at x = 0, and the lanes beside
/// them go on to give the rows they give on their own.
#[test]
fn a_run_whose_series_is_not_finite_fails_alone() {
    let model = scratch("sweep-test", "root.toml");
    std::fs::write(
        &model,
        "name = \"falling root\"\ncoordinates = [\"x\"]\nlagrangian = \"x'^2/2 - x^(3/2)\"\n\
         [initial]\nx = 1.0\n\"x'\" = 0.0\n",
    )
    .unwrap();
    let model = model.to_str().unwrap();
    let (mixed, alone) = (scratch("sweep-test", "root-mixed.csv"), scratch("sweep-test", "root-alone.csv"));
    ok(&["sweep", model, "--until", "0.5", "--grid", "x=-1:1:5", "--no-lyapunov", "--out", mixed.to_str().unwrap()]);
    ok(&["sweep", model, "--until", "0.5", "--grid", "x=1:1:1", "--no-lyapunov", "--out", alone.to_str().unwrap()]);
    let mixed = text(&mixed);
    let rows: Vec<&str> = mixed.lines().skip(2).collect();
    assert_eq!(rows.len(), 5, "{mixed}");
    for row in &rows[..3] {
        assert!(row.ends_with("right-hand side failed at t = 0: the Taylor series is not finite"), "{row}");
    }
    assert!(rows[3].starts_with("3,0.5,0.5,") && rows[3].ends_with(','), "{}", rows[3]);
    let alone = text(&alone);
    let alone = alone.lines().nth(2).unwrap();
    assert_eq!(rows[4].split_once(',').unwrap().1, alone.split_once(',').unwrap().1);
}

/// A sweep whose every run fails found nothing: exit 1 with the first run's
/// reason, every row written all the same.
#[test]
fn a_sweep_whose_every_run_fails_exits_1_with_the_first_reason() {
    let model = scratch("sweep-test", "root-all.toml");
    std::fs::write(
        &model,
        "name = \"falling root\"\ncoordinates = [\"x\"]\nlagrangian = \"x'^2/2 - x^(3/2)\"\n\
         [initial]\nx = 1.0\n\"x'\" = 0.0\n",
    )
    .unwrap();
    let out = scratch("sweep-test", "root-all.csv");
    let r = lagrange(&[
        "sweep",
        model.to_str().unwrap(),
        "--until",
        "0.5",
        "--grid",
        "x=-1:-0.5:3",
        "--no-lyapunov",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(r.code, Some(1), "{}", r.describe());
    assert!(
        r.stderr.contains("every run failed (3); the first, run 0: right-hand side failed at t = 0"),
        "{}",
        r.stderr
    );
    assert_eq!(text(&out).lines().skip(2).count(), 3);
}

/// A row whose parameter values the model refuses (here a hinge axis of length
/// 0 at lam = 0.1 + 0.2 = 0.30000000000000004) fails with the reason `--set`
/// gives for that value, and the rows beside it run as they do alone.
#[test]
fn a_row_at_values_the_model_refuses_fails_with_the_reason() {
    let model = scratch("sweep-test", "hinge.toml");
    std::fs::write(
        &model,
        "name = \"hinge from a parameter\"\ncoordinates = [\"th\"]\ngravity = \"g\"\n\
         [parameters]\nm = 1.0\ng = 9.81\nlam = 1.3\n\
         [[bodies]]\nmass = \"m\"\ninertia = [\"m\", \"m\", \"m\"]\nangle = \"th\"\n\
         axis = [\"lam - 0.3\", \"0\", \"0\"]\ncenter_of_mass = [\"0\", \"0\", \"-1\"]\n\
         [initial]\nth = 0.5\n\"th'\" = 0\n",
    )
    .unwrap();
    let model = model.to_str().unwrap();
    let lam = 0.1 + 0.2;
    let set = lagrange(&["simulate", model, "--until", "1", "--set", &format!("lam={lam:?}")]);
    assert_eq!(set.code, Some(2), "{}", set.describe());
    assert!(set.stderr.contains("the axis has no direction"), "{}", set.stderr);
    let (all, alone) = (scratch("sweep-test", "hinge-all.csv"), scratch("sweep-test", "hinge-alone.csv"));
    ok(&["sweep", model, "--until", "1", "--grid", "lam=0.1:0.5:3", "--no-lyapunov", "--out", all.to_str().unwrap()]);
    ok(&["sweep", model, "--until", "1", "--grid", "lam=0.5:0.5:1", "--no-lyapunov", "--out", alone.to_str().unwrap()]);
    let all = text(&all);
    let rows: Vec<&str> = all.lines().skip(2).collect();
    assert_eq!(rows.len(), 3, "{all}");
    assert!(rows[1].starts_with(&format!("1,{lam:?},")), "{}", rows[1]);
    assert!(rows[1].ends_with(",the axis has no direction (its length is 0)"), "{}", rows[1]);
    for row in [rows[0], rows[2]] {
        let final_th: f64 = row.split(',').nth(3).unwrap().parse().unwrap();
        assert!(row.ends_with(',') && final_th.is_finite(), "{row}");
    }
    // The axis is normalized at every row's values, not only at the file's
    // (where lam − 0.3 = 1): along −x and +x the pendulum swings alike.
    let final_th = |row: &str| row.split(',').nth(3).unwrap().to_string();
    assert_eq!(final_th(rows[0]), final_th(rows[2]));
    let alone = text(&alone);
    let alone = alone.lines().nth(2).unwrap();
    assert_eq!(rows[2].split_once(',').unwrap().1, alone.split_once(',').unwrap().1);
}

/// A grid axis named like a column the sweep writes itself (a parameter
/// `failure`) would write two columns of one name: exit 2 at the parameter.
#[test]
fn an_axis_named_like_a_sweep_column_is_refused() {
    let model = scratch("sweep-test", "named-failure.toml");
    std::fs::write(
        &model,
        "coordinates = [\"x\"]\nlagrangian = \"x'^2/2 - failure*x^2/2\"\n[parameters]\nfailure = 1.0\n\
         [initial]\nx = 1.0\n\"x'\" = 0.0\n",
    )
    .unwrap();
    let model = model.to_str().unwrap();
    ok(&["sweep", model, "--until", "0.1", "--grid", "x=0:1:2", "--no-lyapunov"]);
    let r = lagrange(&["sweep", model, "--until", "0.1", "--grid", "failure=1:2:2", "--no-lyapunov"]);
    assert_eq!(r.code, Some(2), "{}", r.describe());
    assert!(
        r.stderr.contains("named-failure.toml:4:1: the sweep's CSV would have two columns 'failure'"),
        "{}",
        r.stderr
    );
}

#[test]
fn an_axis_of_listed_values_runs_those_values_and_merges_back() {
    let model = repo_root().join("examples/double_pendulum.toml");
    let model = model.to_str().unwrap();
    let whole = scratch("sweep", "listed.csv");
    let args = ["sweep", model, "--until", "0.1", "--grid", "a=0;1;5,g=1.62;9.81", "--no-lyapunov"];
    ok(&[&args[..], &["--out", whole.to_str().unwrap()]].concat());
    let text = text(&whole);
    assert!(
        text.starts_with("# lagrange sweep; model=planar double pendulum; grid=a=0.0;1.0;5.0,g=1.62;9.81;"),
        "{text}"
    );
    let values: Vec<(String, String)> = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("run"))
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            (cells[1].to_string(), cells[2].to_string())
        })
        .collect();
    let want: Vec<(String, String)> =
        [("0.0", "1.62"), ("0.0", "9.81"), ("1.0", "1.62"), ("1.0", "9.81"), ("5.0", "1.62"), ("5.0", "9.81")]
            .iter()
            .map(|(a, g)| (a.to_string(), g.to_string()))
            .collect();
    assert_eq!(values, want);
    // Shards of it merge to the whole, the provenance read back from the header.
    let parts: Vec<_> = (0..2).map(|i| scratch("sweep", &format!("listed_{i}.csv"))).collect();
    for (i, part) in parts.iter().enumerate() {
        ok(&[&args[..], &["--shard", &format!("{i}/2"), "--out", part.to_str().unwrap()]].concat());
    }
    let merged = scratch("sweep", "listed_merged.csv");
    ok(&["sweep", "--merge", merged.to_str().unwrap(), parts[0].to_str().unwrap(), parts[1].to_str().unwrap()]);
    assert_eq!(text_rows(&merged), text_rows(&whole));
}

/// The rows of a sweep's CSV without its timing-free header line.
fn text_rows(path: &Path) -> Vec<String> {
    text(path).lines().filter(|l| !l.starts_with('#')).map(str::to_string).collect()
}
