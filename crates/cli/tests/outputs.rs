//! Outputs never clobber: a file another run is writing (it holds the lock a
//! streamed CSV holds), a hard link to the model and a file the model names (a
//! body file, by its path or a link) are refused by every output of every
//! command, with exit 2, before anything is written.

use crate::common;

use crate::common::{run, scratch};
use std::fs::File;
use std::path::Path;

/// Each command with each of its outputs as `{}`.
const COMMANDS: [&[&str]; 10] = [
    &["simulate", "examples/pendulum.toml", "--until", "1", "--out", "{}"],
    &["simulate", "examples/pendulum.toml", "--until", "1", "--plot", "{}"],
    &["report", "examples/pendulum.toml", "--until", "1", "-o", "{}"],
    &["sweep", "examples/pendulum.toml", "--until", "1", "--grid", "ph=0.1:0.2:2", "--out", "{}"],
    &["sweep", "examples/pendulum.toml", "--until", "1", "--grid", "ph=0.1:0.2:2,ph'=0:1:2", "--heatmap", "{}"],
    &["orbit", "examples/kepler.toml", "--plot", "{}"],
    &["modes", "examples/coupled_oscillators.toml", "--animate", "{}"],
    &["top", "examples/tops/heavy_top.toml", "--plot", "{}"],
    &["extremal", "examples/extremal/brachistochrone.toml", "--plot", "{}"],
    &["simulate", "examples/pendulum.toml", "--until", "1", "--out", "{}", "--plot", "{}"],
];

fn with_output<'a>(command: &[&'a str], out: &'a str) -> Vec<&'a str> {
    command.iter().map(|a| if *a == "{}" { out } else { a }).collect()
}

#[test]
fn every_output_honours_the_lock_of_a_file_being_written() {
    let path = scratch("outputs", "streamed.csv");
    let rows = "t,x\n0,1\n";
    for command in COMMANDS {
        std::fs::write(&path, rows).unwrap();
        let held = File::open(&path).unwrap();
        held.lock().unwrap();
        let r = run(&with_output(command, path.to_str().unwrap()));
        assert_eq!(r.code, Some(2), "{}", r.describe());
        assert!(r.stderr.contains("in use by another run"), "{}", r.describe());
        assert_eq!(std::fs::read_to_string(&path).unwrap(), rows, "{command:?} wrote into a locked file");
        drop(held);
    }
}

#[test]
fn a_hard_link_to_the_model_is_the_model() {
    let model = scratch("outputs-link", "m.toml");
    let text = std::fs::read_to_string(common::repo_root().join("examples/pendulum.toml")).unwrap();
    std::fs::write(&model, &text).unwrap();
    let link = model.with_file_name("h.csv");
    for command in [
        ["simulate", "{m}", "--until", "1", "--out", "{}"].as_slice(),
        &["simulate", "{m}", "--until", "1", "--plot", "{}"],
        &["report", "{m}", "--until", "1", "-o", "{}"],
        &["sweep", "{m}", "--until", "1", "--grid", "ph=0.1:0.2:2", "--out", "{}"],
    ] {
        let _ = std::fs::remove_file(&link);
        std::fs::hard_link(&model, &link).unwrap();
        let args: Vec<&str> = with_output(command, link.to_str().unwrap())
            .into_iter()
            .map(|a| if a == "{m}" { model.to_str().unwrap() } else { a })
            .collect();
        let r = run(&args);
        assert_eq!(r.code, Some(2), "{}", r.describe());
        assert!(r.stderr.contains("is an input of this command"), "{}", r.describe());
        assert_eq!(std::fs::read_to_string(&model).unwrap(), text, "{command:?} changed the model");
    }
    assert!(Path::new(&model).exists());
}

#[test]
fn a_file_the_model_names_is_an_input_too() {
    // The cone top reads its mass and inertia from a body file beside it.
    let model = scratch("outputs-named", "cone_top.toml");
    let body = model.with_file_name("cone_top_body.toml");
    for (from, to) in [("examples/tops/cone_top.toml", &model), ("examples/tops/cone_top_body.toml", &body)] {
        std::fs::copy(common::repo_root().join(from), to).unwrap();
    }
    let text = std::fs::read_to_string(&body).unwrap();
    let link = body.with_file_name("b.svg");
    let spelled = body.with_file_name(".").join("cone_top_body.toml");
    for out in [&body, &spelled, &link] {
        for command in [
            ["simulate", "{m}", "--until", "0.1", "--out", "{}"].as_slice(),
            &["simulate", "{m}", "--until", "0.1", "--plot", "{}"],
            &["report", "{m}", "--until", "0.1", "-o", "{}"],
            &["top", "{m}", "--plot", "{}"],
            &["modes", "{m}", "--animate", "{}"],
        ] {
            let _ = std::fs::remove_file(&link);
            std::fs::hard_link(&body, &link).unwrap();
            let args: Vec<&str> = with_output(command, out.to_str().unwrap())
                .into_iter()
                .map(|a| if a == "{m}" { model.to_str().unwrap() } else { a })
                .collect();
            let r = run(&args);
            assert_eq!(r.code, Some(2), "{}", r.describe());
            assert!(r.stderr.contains("is an input of this command"), "{}", r.describe());
            assert_eq!(std::fs::read_to_string(&body).unwrap(), text, "{args:?} changed the body file");
        }
    }
}

#[test]
fn a_huge_end_time_is_echoed_as_written() {
    let model = scratch("outputs", "free.toml");
    std::fs::write(&model, "coordinates = [\"x\"]\nkinetic = \"x'^2/2\"\n[initial]\nx = 0\n\"x'\" = 0\n").unwrap();
    let r = common::ok(&["simulate", model.to_str().unwrap(), "--until", "1e300", "--samples", "3"]);
    assert!(r.stdout.contains("reached t = 1e300\n"), "{}", r.describe());
    assert!(!r.stdout.contains("0000000000000000000000"), "{}", r.describe());
}
