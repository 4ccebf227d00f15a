//! The guide holds together: every relative link of the README and of the pages of `docs/`
//! (and of the other READMEs) leads to a file of the repository (and, with `#anchor`, to a
//! heading of it), every page of `docs/` is reachable from the README, and every command of
//! the docs' shell examples (`cargo run … -- ARGS`, `admm-ta ARGS`) is one the command line
//! accepts.

use std::collections::BTreeSet;
use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The Markdown files the guide is made of.
fn pages() -> Vec<PathBuf> {
    let mut pages = vec![
        root().join("README.md"),
        root().join("bench/README.md"),
        root().join("python/README.md"),
    ];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    pages.extend(docs);
    pages
}

/// The text outside fenced code blocks and inline code.
fn prose(text: &str) -> String {
    let mut out = String::new();
    let mut fenced = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        // Inline code holds no links.
        let mut inline = false;
        for c in line.chars() {
            if c == '`' {
                inline = !inline;
            } else if !inline {
                out.push(c);
            }
        }
        out.push('\n');
    }
    out
}

/// Every `[text](target)` of `text`'s prose.
fn links(text: &str) -> Vec<String> {
    let prose = prose(text);
    let mut found = Vec::new();
    let mut rest = prose.as_str();
    while let Some(at) = rest.find("](") {
        let after = &rest[at + 2..];
        if let Some(end) = after.find(')') {
            found.push(after[..end].trim().to_string());
        }
        rest = &rest[at + 2..];
    }
    found
}

/// GitHub's anchor of a heading: lower case, spaces to dashes, other punctuation dropped.
fn anchor(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

fn anchors(text: &str) -> BTreeSet<String> {
    let mut fenced = false;
    let mut found = BTreeSet::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
        } else if !fenced && line.starts_with('#') {
            found.insert(anchor(line.trim_start_matches('#')));
        }
    }
    found
}

fn relative(target: &str) -> bool {
    !(target.starts_with("http://")
        || target.starts_with("https://")
        || target.starts_with("mailto:")
        || target.is_empty())
}

#[test]
fn every_relative_link_resolves() {
    let mut broken = Vec::new();
    for page in pages() {
        let text = std::fs::read_to_string(&page).unwrap();
        for target in links(&text).into_iter().filter(|t| relative(t)) {
            let (file, fragment) = match target.split_once('#') {
                Some((file, fragment)) => (file, Some(fragment)),
                None => (target.as_str(), None),
            };
            let path = if file.is_empty() {
                page.clone()
            } else {
                page.parent().unwrap().join(file)
            };
            if !path.exists() {
                broken.push(format!("{}: {target}", page.display()));
                continue;
            }
            if let Some(fragment) = fragment
                && path.extension().is_some_and(|e| e == "md")
                && !anchors(&std::fs::read_to_string(&path).unwrap()).contains(fragment)
            {
                broken.push(format!("{}: {target} (no such heading)", page.display()));
            }
        }
    }
    assert!(broken.is_empty(), "broken links: {broken:#?}");
}

#[test]
fn every_page_of_the_guide_is_reachable_from_the_readme() {
    let mut reached = BTreeSet::new();
    let mut todo = vec![root().join("README.md")];
    while let Some(page) = todo.pop() {
        let page = page.canonicalize().unwrap();
        if !reached.insert(page.clone()) {
            continue;
        }
        let text = std::fs::read_to_string(&page).unwrap();
        for target in links(&text).into_iter().filter(|t| relative(t)) {
            let file = target.split('#').next().unwrap();
            let path = page.parent().unwrap().join(file);
            if !file.is_empty() && file.ends_with(".md") && path.exists() {
                todo.push(path);
            }
        }
    }
    let docs = root().join("docs").canonicalize().unwrap();
    let unreached: Vec<PathBuf> = pages()
        .into_iter()
        .map(|p| p.canonicalize().unwrap())
        .filter(|p| p.starts_with(&docs) && !reached.contains(p))
        .collect();
    assert!(
        unreached.is_empty(),
        "not reachable from the README: {unreached:?}"
    );
}

/// The words of a shell command line (quotes removed), up to a pipe, a redirection or a
/// second command.
fn words(line: &str) -> Vec<String> {
    let mut words = Vec::new();
    let mut word = String::new();
    let mut quote: Option<char> = None;
    let mut any = false;
    for c in line.chars() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), c) => word.push(c),
            (None, '\'' | '"') => {
                quote = Some(c);
                any = true;
            }
            (None, '|' | '>' | '<' | ';' | '&') => break,
            (None, c) if c.is_whitespace() => {
                if !word.is_empty() || any {
                    words.push(std::mem::take(&mut word));
                }
                any = false;
            }
            (None, c) => word.push(c),
        }
    }
    if !word.is_empty() || any {
        words.push(word);
    }
    words
}

/// The lines of `text`, those ending in a backslash joined with the next (a shell
/// command continued).
fn joined_lines(text: &str) -> Vec<String> {
    let mut lines = Vec::new();
    let mut pending = String::new();
    for line in text.lines() {
        match line.strip_suffix('\\') {
            Some(start) => {
                pending.push_str(start);
                pending.push(' ');
            }
            None => {
                pending.push_str(line);
                lines.push(std::mem::take(&mut pending));
            }
        }
    }
    lines
}

/// The `admm-ta` arguments of a shell line, if it runs the command line.
fn command_of(line: &str) -> Option<Vec<String>> {
    let line = line.trim().trim_start_matches("$ ");
    if line.starts_with('#') {
        return None;
    }
    let line = match line.find(" # ") {
        Some(at) => &line[..at],
        None => line,
    };
    let words = words(line);
    let args = match words.first().map(String::as_str) {
        Some("admm-ta") => words[1..].to_vec(),
        Some(program) if program.ends_with("/admm-ta") => words[1..].to_vec(),
        Some("cargo") if words.get(1).is_some_and(|w| w == "run") => {
            // Another package's binary or an example is not the command line.
            if words
                .iter()
                .any(|w| w == "-p" || w == "--example" || w == "--package")
            {
                return None;
            }
            let at = words.iter().position(|w| w == "--")?;
            words[at + 1..].to_vec()
        }
        _ => return None,
    };
    Some(args)
}

#[test]
fn every_command_of_the_docs_examples_is_accepted() {
    let mut refused = Vec::new();
    let mut checked = 0;
    // The lab notes keep their synopses (`[--flag]`) as they were measured.
    let lab_notes = root().join("bench/README.md");
    for page in pages().into_iter().filter(|p| *p != lab_notes) {
        let text = std::fs::read_to_string(&page).unwrap();
        let mut shell = false;
        let mut fenced = false;
        for line in joined_lines(&text) {
            let line = line.as_str();
            let trimmed = line.trim_start();
            if let Some(info) = trimmed.strip_prefix("```") {
                fenced = !fenced;
                shell = fenced && matches!(info.trim(), "sh" | "bash" | "shell" | "console");
                continue;
            }
            if !shell {
                continue;
            }
            let Some(args) = command_of(line) else {
                continue;
            };
            checked += 1;
            let argv = std::iter::once("admm-ta".to_string()).chain(args.iter().cloned());
            if let Err(error) = admm_ta::command_line::parse(argv)
                && error.use_stderr()
            {
                refused.push(format!(
                    "{}: {line}\n    {}",
                    page.display(),
                    admm_ta::command_line::one_line(&error)
                ));
            }
        }
    }
    assert!(checked >= 20, "only {checked} commands found in the docs");
    assert!(
        refused.is_empty(),
        "refused commands:\n{}",
        refused.join("\n")
    );
}

#[test]
fn the_readme_is_a_front_door() {
    let text = std::fs::read_to_string(root().join("README.md")).unwrap();
    let lines = text.lines().count();
    assert!(
        lines <= 300,
        "README.md has {lines} lines: the details go to docs/"
    );
    for command in ["cargo run --release -- demo", "./test"] {
        assert!(text.contains(command), "the README names {command}");
    }
}
