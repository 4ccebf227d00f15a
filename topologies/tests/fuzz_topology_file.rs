//! Fuzzing the topology file parser, as property tests that run in CI: arbitrary text never
//! panics; generated files with random edges parse exactly when they describe a simple graph
//! on the declared robots, and then into that graph.

use admm_ta_topologies::file::parse;
use proptest::prelude::*;
use std::path::Path;

proptest! {
    #[test]
    fn arbitrary_text_never_panics(text in "\\PC{0,300}") {
        let _ = parse(&text, Path::new("fuzz.toml"));
    }

    #[test]
    fn toml_like_text_never_panics(
        robots in prop_oneof![Just("0".to_string()), Just("-1".into()), Just("1e3".into()),
                              Just("18446744073709551616".into()), (0u64..50).prop_map(|v| v.to_string())],
        edges in prop::collection::vec(("[0-9-]{1,3}", "[0-9x]{1,3}"), 0..8),
        extra in prop_oneof![Just(String::new()), Just("name = \"x\"\n".into()), Just("[[".into())],
    ) {
        let list: Vec<String> = edges.iter().map(|(a, b)| format!("[{a}, {b}]")).collect();
        let text = format!("robots = {robots}\nedges = [{}]\n{extra}", list.join(", "));
        let _ = parse(&text, Path::new("fuzz.toml"));
    }

    #[test]
    fn files_parse_exactly_when_they_are_simple_graphs(
        robots in 1usize..9,
        edges in prop::collection::vec((0usize..10, 0usize..10), 0..20),
    ) {
        let list: Vec<String> = edges.iter().map(|(a, b)| format!("[{a}, {b}]")).collect();
        let text = format!("robots = {robots}\nedges = [{}]\n", list.join(", "));
        let valid = {
            let mut seen = std::collections::HashSet::new();
            edges.iter().all(|&(a, b)| {
                a < robots && b < robots && a != b && seen.insert((a.min(b), a.max(b)))
            })
        };
        match parse(&text, Path::new("fuzz.toml")) {
            Ok(graph) => {
                prop_assert!(valid, "accepted {text}");
                prop_assert_eq!(graph.robots(), robots);
                for &(a, b) in &edges {
                    prop_assert!(graph.neighbours(a).contains(&b));
                }
            }
            Err(_) => prop_assert!(!valid, "refused a valid file: {text}"),
        }
    }
}
