//! Cost files as people have them: each export reads to the same optimum as the plain file,
//! names show in the report, standard input works, and the refusals name line and column.

use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, Output, Stdio};

/// The plain 4×4 problem every variant below encodes.
const PLAIN: &str = "62.29,74.18,11.5,40\n10,20,30,40\n7.5,3.25,99,1e1\n5,6,7,8\n";

fn dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("admm-ta-cost-files-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn file(name: &str, text: &str) -> String {
    let path = dir().join(name);
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

/// `admm-ta solve --json --check ARGS` with `stdin` on its standard input.
fn solve(args: &[&str], stdin: Option<&str>) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_admm-ta"))
        .args(["solve", "--json", "--check"])
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut input = child.stdin.take().unwrap();
    // A refusal that needs no input (two readers of standard input)
    // may exit before reading it: a closed pipe is not a failure.
    match input.write_all(stdin.unwrap_or("").as_bytes()) {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {}
        other => other.unwrap(),
    }
    drop(input);
    child.wait_with_output().unwrap()
}

fn report(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn every_common_export_solves_to_the_plain_files_optimum() {
    let plain = report(&solve(&["--costs", &file("plain.csv", PLAIN)], None));
    let optimum = plain["cost"].as_f64().unwrap();
    assert!(plain.get("robot_names").is_none() && plain.get("task_names").is_none());
    let pandas = ",dock_A,dock_B,dock_C,dock_D\nuav1,62.29,74.18,11.5,40\nuav2,10,20,30,40\nuav3,7.5,3.25,99,1e1\nuav4,5,6,7,8\n";
    let variants = [
        ("pandas.csv", pandas.to_string()),
        ("header.csv", format!("t0,t1,t2,t3\n{PLAIN}")),
        (
            "quoted.csv",
            PLAIN
                .lines()
                .map(|l| {
                    l.split(',')
                        .map(|c| format!("\"{c}\""))
                        .collect::<Vec<_>>()
                        .join(",")
                })
                .collect::<Vec<_>>()
                .join("\r\n"),
        ),
        ("tabs.tsv", PLAIN.replace(',', "\t")),
        ("semicolons.csv", PLAIN.replace(',', ";")),
        ("trailing.csv", PLAIN.replace('\n', ",\n")),
        ("bom.csv", format!("\u{feff}# exported\n\n{PLAIN}")),
        (
            "costs.json",
            r#"{"costs": [[62.29,74.18,11.5,40],[10,20,30,40],[7.5,3.25,99,10],[5,6,7,8]]}"#
                .to_string(),
        ),
    ];
    for (name, text) in variants {
        let read = report(&solve(&["--costs", &file(name, &text)], None));
        assert_eq!(read["cost"].as_f64().unwrap(), optimum, "{name}");
        assert_eq!(read["assignment"], plain["assignment"], "{name}");
        assert_eq!(read["check"]["optimal"], true, "{name}");
    }
    // Standard input, as `python gen.py | admm-ta solve --costs -`.
    let piped = report(&solve(&["--costs", "-"], Some(pandas)));
    assert_eq!(piped["cost"].as_f64().unwrap(), optimum);
    assert_eq!(
        piped["robot_names"],
        serde_json::json!(["uav1", "uav2", "uav3", "uav4"])
    );
    assert_eq!(piped["task_names"][0], "dock_A");
    let stdin = report(&solve(&["--costs", "/dev/stdin"], Some(PLAIN)));
    assert_eq!(stdin["cost"].as_f64().unwrap(), optimum);
}

#[test]
fn names_show_in_the_text_report_and_name_forbidden_pairs() {
    let costs = file("named.csv", ",dock_A,dock_B\nuav3,1,9\nuav4,9,1\n");
    let forbidden = file("named-pairs.csv", "uav3,dock_A\n");
    let out = Command::new(env!("CARGO_BIN_EXE_admm-ta"))
        .args(["solve", "--costs", &costs, "--forbidden", &forbidden])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("uav3 → dock_B, uav4 → dock_A"), "{text}");
    // JSON nulls are forbidden pairs, also when maximising (they become -inf there).
    let json = file(
        "profits.json",
        r#"{"costs": [[9, null], [1, 2]], "robots": ["a", "b"], "tasks": ["x", "y"]}"#,
    );
    let profits = report(&solve(&["--costs", &json, "--maximize"], None));
    assert_eq!(profits["assignment"], serde_json::json!([0, 1]));
    assert_eq!(profits["cost"].as_f64().unwrap(), 11.0);
}

#[test]
fn a_topology_file_names_robots_as_the_cost_file_does() {
    let pandas = ",dock_A,dock_B,dock_C,dock_D\nuav1,62.29,74.18,11.5,40\nuav2,10,20,30,40\nuav3,7.5,3.25,99,1e1\nuav4,5,6,7,8\n";
    let costs = file("chain-costs.csv", pandas);
    let plain = report(&solve(&["--costs", &file("chain-plain.csv", PLAIN)], None));
    // A chain uav2 – uav1 – uav4 – uav3, names and numbers mixed.
    let chain = file(
        "named-chain.toml",
        "robots = 4\nedges = [[\"uav2\", \"uav1\"], [\"uav1\", 3], [\"uav4\", \"uav3\"]]\n",
    );
    let named = report(&solve(&["--costs", &costs, "--topology", &chain], None));
    assert_eq!(named["cost"], plain["cost"]);
    assert_eq!(named["check"]["optimal"], true);
    // The same edges by number: the same graph, so the same rounds.
    let numbered = file(
        "numbered-chain.toml",
        "robots = 4\nedges = [[1, 0], [0, 3], [3, 2]]\n",
    );
    let by_number = report(&solve(&["--costs", &costs, "--topology", &numbered], None));
    assert_eq!(by_number["iterations"], named["iterations"]);
    assert_eq!(by_number["assignment"], named["assignment"]);
    // A name the costs do not have, or names with unnamed costs: exit 2, one line naming
    // the edge and the name.
    let typo = file(
        "typo-chain.toml",
        "robots = 4\nedges = [[\"uav1\", \"uav2\"], [\"uav2\", \"uva3\"], [2, 3]]\n",
    );
    let plain_costs = file("chain-plain2.csv", PLAIN);
    for (costs, needle) in [
        (
            &costs,
            "edge 1: no robot is named 'uva3' (the robots are uav1, uav2, uav3, uav4)",
        ),
        (
            &plain_costs,
            "edge 0: robot 'uav1' is named, but the costs name no robots",
        ),
    ] {
        let out = solve(&["--costs", costs, "--topology", &typo], None);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(needle), "{stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    }
}

#[test]
fn bad_cost_files_are_refused_naming_line_and_column() {
    for (text, needle) in [
        ("1,2\n3,x\n", "line 2, column 2: 'x' is not a number"),
        ("# c\n\n1,2\n3\n", "line 4 has 1 values"),
        ("1;2,5\n3;4\n", "decimal comma"),
        (",a,a\nr,1,2\n", "two tasks are called 'a'"),
        ("1,nan\n", "NaN"),
        ("[[1, true]]", "not a cost"),
    ] {
        let out = solve(&["--costs", "-"], Some(text));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{text:?}: {stderr}");
        assert!(stderr.contains(needle), "{text:?}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    }
    // Both from standard input cannot be.
    let out = solve(&["--costs", "-", "--forbidden", "-"], Some(PLAIN));
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn a_full_disk_is_reported_once() {
    let out = Command::new(env!("CARGO_BIN_EXE_admm-ta"))
        .args(["solve", "--robots", "3", "--tasks", "3", "--json"])
        .stdout(std::fs::File::create("/dev/full").unwrap())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert_eq!(
        stderr.matches("No space left on device").count(),
        1,
        "{stderr}"
    );
}
