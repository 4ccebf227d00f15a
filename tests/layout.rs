//! The workspace's layout rules, checked on the sources of every crate at test time (the
//! crates are the workspace's members and the root package; each crate's files are found by
//! following `mod` declarations from its `src/lib.rs` or `src/main.rs`; tests, examples and
//! benches are not sources):
//!
//! (a) every source file belongs to a crate (a file no `mod` reaches is dead);
//! (b) no import cycle between the files of a crate: a file is a module (`mod.rs` stands for
//!     its folder), and a module depends on every module it names by a path — `crate::…`,
//!     `super::…` and `self::…` (outside inline modules such as `mod tests`), or a child
//!     module's name (`child::…`) — in `use` trees such as `use crate::{a, b::{c, d}}`, in
//!     paths written inline, and under `#[cfg(…)]` as well (both builds count). Comments (doc
//!     links included) and string literals are not code and do not count. A path names the
//!     longest module it starts with (`crate::ipc::exchange::IpcExchange` names
//!     `ipc::exchange`);
//! (c) no file above 500 lines unless its module doc has a line starting with `//! Size:`
//!     that says why;
//! (d) in the transport crate, no transport module (`sim`, `threads`, `shm`, `ipc`, `uds`,
//!     `zenoh_net`, each with its submodules) names another transport: what several of them
//!     share sits below them; every transport is a folder of the same shape (`mod.rs` with
//!     its declaration, `exchange.rs`, `process.rs`);
//! (e) within the orchestration crate (`runtime`) and the transport crate (`transport`),
//!     data flows one way: a module names modules of its own layer or of lower layers only
//!     ([`RUNTIME_LAYERS`] and [`TRANSPORT_LAYERS`], the layers of each crate's `lib.rs`; a
//!     new top-level module must be placed in one). Between the two, Cargo keeps the
//!     direction: the runtime depends on the transport crate, never the reverse;
//! (f) the registries close: outside tests, the runtime, the transports and the benchmarks
//!     name no concrete method (no `Method::Primal`, no `methods::primal::…`: the methods
//!     are those of the registry in `agents/src/methods/mod.rs`), and the process
//!     orchestration (`runtime/src/process/`) names no concrete transport (neither a
//!     transport module nor a `Transport::Ipc`);
//! (g) no function of the runtime, the transports or the agents returns `Result<_, String>`:
//!     errors are typed, one type per operation.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Stands in [`TRANSPORT_LAYERS`] for the transports: the modules the registry of
/// `transport/src/registry.rs` names ([`transports`]), so a new transport is placed by its
/// registry line alone.
const TRANSPORT_MODULES: &str = "<the transports of the registry>";

/// The orchestration crate's layers, top to bottom, by top-level module (with their
/// submodules).
const RUNTIME_LAYERS: &[&[&str]] = &[
    // Entry points.
    &[
        "solve",
        "surveillance",
        "probe_run",
        "team",
        "host",
        "standing",
        "observe",
    ],
    // The team runner.
    &["runner"],
    // Process orchestration.
    &["process"],
    // Configuration: options, workloads.
    &["options", "workload"],
];

/// The transport crate's layers, top to bottom.
const TRANSPORT_LAYERS: &[&[&str]] = &[
    // The registry of transports.
    &["registry"],
    // The transports.
    &[TRANSPORT_MODULES],
    // Shared mechanisms below every transport.
    &[
        "exchange",
        "board",
        "liveness",
        "logging",
        "signals",
        "timeline",
        "fault",
        "wait",
        "futex",
        "latency",
        "usage",
        "endpoint",
        "error_text",
    ],
];

/// The files every transport folder has.
const TRANSPORT_FILES: [&str; 3] = ["mod.rs", "exchange.rs", "process.rs"];

/// Longest file without a stated reason.
const MAX_LINES: usize = 500;

/// One source file of a crate.
struct SourceFile {
    path: PathBuf,
    /// `crate` for the crate root, else the module path, e.g. `ipc::exchange`.
    module: String,
    text: String,
    /// The text with comments and literals blanked ([`code_only`]).
    code: String,
    /// The modules it declares with `mod NAME;` (its children in other files).
    children: Vec<String>,
}

/// One crate of the workspace: a library or a binary.
struct Crate {
    /// `runtime (lib)`, `. (bin)`: the package's folder and the kind of target.
    name: String,
    /// The package's folder relative to the workspace root (`.` for the root package).
    package: String,
    files: Vec<SourceFile>,
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The package folders: the root and the workspace's members.
fn packages() -> Vec<String> {
    let manifest = std::fs::read_to_string(root().join("Cargo.toml")).unwrap();
    let start = manifest
        .find("members = [")
        .expect("a workspace member list");
    let list = &manifest[start..start + manifest[start..].find(']').unwrap()];
    let mut packages = vec![".".to_string()];
    packages.extend(list.split('"').skip(1).step_by(2).map(String::from));
    assert!(packages.len() >= 5, "packages: {packages:?}");
    packages
}

/// Every crate: each package's `src/lib.rs` and `src/main.rs` with the files they reach.
fn crates() -> Vec<Crate> {
    let mut crates = Vec::new();
    for package in packages() {
        for (kind, file) in [("lib", "lib.rs"), ("bin", "main.rs")] {
            let path = root().join(&package).join("src").join(file);
            if path.exists() {
                crates.push(Crate {
                    name: format!("{package} ({kind})"),
                    package: package.clone(),
                    files: crate_files(&path),
                });
            }
        }
    }
    crates
}

/// The files of the crate rooted at `root_file`, found by following `mod NAME;`.
fn crate_files(root_file: &Path) -> Vec<SourceFile> {
    let mut files = Vec::new();
    let mut pending = vec![(root_file.to_path_buf(), "crate".to_string())];
    while let Some((path, module)) = pending.pop() {
        let text =
            std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let code = code_only(&text);
        let children = declared_modules(&code);
        // A crate root and a `mod.rs` keep their children beside them; `a.rs` in `a/`.
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        let dir = if module == "crate" || name == "mod" {
            path.parent().unwrap().to_path_buf()
        } else {
            path.with_extension("")
        };
        for child in &children {
            let file = dir.join(format!("{child}.rs"));
            let file = if file.exists() {
                file
            } else {
                dir.join(child).join("mod.rs")
            };
            assert!(file.exists(), "{}: mod {child} has no file", path.display());
            let child_module = if module == "crate" {
                child.clone()
            } else {
                format!("{module}::{child}")
            };
            pending.push((file, child_module));
        }
        files.push(SourceFile {
            path,
            module,
            text,
            code,
            children,
        });
    }
    files
}

/// The modules `code` declares in other files: `mod NAME;` (not inline `mod NAME { … }`).
fn declared_modules(code: &str) -> Vec<String> {
    let chars: Vec<char> = code.chars().collect();
    let mut names = Vec::new();
    let mut i = 0;
    while let Some(found) = find(&chars, i, "mod") {
        i = found + 3;
        let before = found.checked_sub(1).map(|p| chars[p]);
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        if !chars.get(i).is_some_and(|c| c.is_whitespace()) {
            continue;
        }
        if let Some((name, end)) = identifier(&chars, skip_space(&chars, i))
            && chars.get(skip_space(&chars, end)) == Some(&';')
        {
            names.push(name);
        }
    }
    names
}

/// `source` with comments, string literals and character literals blanked out (replaced by
/// spaces, newlines kept), so that only code is left.
fn code_only(source: &str) -> String {
    let chars: Vec<char> = source.chars().collect();
    let mut out = String::with_capacity(source.len());
    let blank = |c: char| if c == '\n' { '\n' } else { ' ' };
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let next = chars.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < chars.len() && chars[i] != '\n' {
                out.push(' ');
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            // Block comments nest in Rust.
            let mut depth = 0;
            while i < chars.len() {
                if chars[i] == '/' && chars.get(i + 1) == Some(&'*') {
                    depth += 1;
                    out.push_str("  ");
                    i += 2;
                } else if chars[i] == '*' && chars.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    out.push_str("  ");
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    out.push(blank(chars[i]));
                    i += 1;
                }
            }
        } else if let Some(hashes) = raw_string_start(&chars, i) {
            // r"…", r#"…"#, br"…": ends at a quote followed by as many hashes.
            let open = chars[i..].iter().position(|&c| c == '"').unwrap() + i;
            let closing: Vec<char> = std::iter::once('"')
                .chain(std::iter::repeat_n('#', hashes))
                .collect();
            let mut j = open + 1;
            while j < chars.len() && !chars[j..].starts_with(&closing) {
                j += 1;
            }
            let end = (j + closing.len()).min(chars.len());
            out.extend(chars[i..end].iter().map(|&c| blank(c)));
            i = end;
        } else if c == '"' {
            out.push(' ');
            i += 1;
            while i < chars.len() && chars[i] != '"' {
                let skip = if chars[i] == '\\' { 2 } else { 1 };
                for k in 0..skip {
                    if let Some(&c) = chars.get(i + k) {
                        out.push(blank(c));
                    }
                }
                i += skip;
            }
            out.push(' ');
            i += 1;
        } else if c == '\'' && next == Some('\\') {
            // An escaped character literal: '\n', '\'', '\u{…}'.
            let end = chars[i + 2..]
                .iter()
                .position(|&c| c == '\'')
                .map_or(chars.len(), |p| i + 2 + p + 1);
            out.extend(std::iter::repeat_n(' ', end - i));
            i = end;
        } else if c == '\'' && chars.get(i + 2) == Some(&'\'') {
            // A one-character literal ('a'); a lifetime ('a) has no closing quote.
            out.push_str("   ");
            i += 3;
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

/// The number of `#`s of a raw string literal starting at `i`, if one does.
fn raw_string_start(chars: &[char], i: usize) -> Option<usize> {
    let before = i.checked_sub(1).map(|p| chars[p]);
    if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
        return None;
    }
    let mut j = i;
    if chars.get(j) == Some(&'b') {
        j += 1;
    }
    if chars.get(j) != Some(&'r') {
        return None;
    }
    j += 1;
    let hashes = chars[j..].iter().take_while(|&&c| c == '#').count();
    (chars.get(j + hashes) == Some(&'"')).then_some(hashes)
}

/// The spans of the inline modules of `code` (`mod NAME { … }`), from `mod` to the closing
/// brace.
fn inline_modules(chars: &[char]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut i = 0;
    while let Some(found) = find(chars, i, "mod") {
        i = found + 3;
        let before = found.checked_sub(1).map(|p| chars[p]);
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let Some((_, end)) = identifier(chars, skip_space(chars, i)) else {
            continue;
        };
        let open = skip_space(chars, end);
        if chars.get(open) != Some(&'{') {
            continue;
        }
        let mut depth = 0;
        let mut close = open;
        for (k, &c) in chars.iter().enumerate().skip(open) {
            match c {
                '{' => depth += 1,
                '}' => depth -= 1,
                _ => {}
            }
            if depth == 0 {
                close = k;
                break;
            }
        }
        spans.push((found, close));
    }
    spans
}

/// Every module path `code` (already stripped by [`code_only`]) names, as segments from the
/// crate root: paths after `crate::`; after `super::` and `self::` outside inline modules,
/// relative to `module` (the file's module, `[]` for the crate root); and after the name of
/// one of its `children`. `use crate::{a, b::{c, d}}` gives `a`, `b::c` and `b::d`.
fn module_paths(code: &str, module: &[String], children: &[String]) -> Vec<Vec<String>> {
    let chars: Vec<char> = code.chars().collect();
    let inline = inline_modules(&chars);
    let mut paths = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let Some((word, end)) = identifier(&chars, i) else {
            i += 1;
            continue;
        };
        let start = i;
        i = end;
        let before = start.checked_sub(1).map(|p| chars[p]);
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '$' || c == ':') {
            continue;
        }
        let mut j = skip_space(&chars, end);
        if !chars[j..].starts_with(&[':', ':']) {
            continue;
        }
        j += 2;
        let nested = inline.iter().any(|&(a, b)| a < start && start < b);
        let mut prefix: Vec<String> = match word.as_str() {
            "crate" => Vec::new(),
            "self" | "super" if nested => continue,
            "self" => module.to_vec(),
            "super" => {
                let mut parent = module[..module.len().saturating_sub(1)].to_vec();
                // `super::super::…`
                while let Some((next, end)) = identifier(&chars, skip_space(&chars, j))
                    && next == "super"
                    && chars[skip_space(&chars, end)..].starts_with(&[':', ':'])
                {
                    parent.pop();
                    j = skip_space(&chars, end) + 2;
                }
                parent
            }
            child if !nested && children.iter().any(|c| c == child) => {
                let mut path = module.to_vec();
                path.push(child.to_string());
                path
            }
            _ => continue,
        };
        i = parse_tree(&chars, j, &mut prefix, &mut paths).max(i);
    }
    paths
}

fn find(chars: &[char], from: usize, word: &str) -> Option<usize> {
    let word: Vec<char> = word.chars().collect();
    (from..chars.len().saturating_sub(word.len() - 1)).find(|&i| chars[i..].starts_with(&word))
}

fn skip_space(chars: &[char], mut i: usize) -> usize {
    while i < chars.len() && chars[i].is_whitespace() {
        i += 1;
    }
    i
}

fn identifier(chars: &[char], i: usize) -> Option<(String, usize)> {
    let start = chars
        .get(i)
        .filter(|c| c.is_alphabetic() || **c == '_')
        .map(|_| i)?;
    let mut end = start;
    while end < chars.len() && (chars[end].is_alphanumeric() || chars[end] == '_') {
        end += 1;
    }
    Some((chars[start..end].iter().collect(), end))
}

/// Parses a use tree (or an inline path) at `i` below `prefix`; pushes every complete path.
/// Returns the position after the tree.
fn parse_tree(
    chars: &[char],
    i: usize,
    prefix: &mut Vec<String>,
    paths: &mut Vec<Vec<String>>,
) -> usize {
    let mut i = skip_space(chars, i);
    match chars.get(i) {
        Some('{') => {
            i += 1;
            loop {
                i = skip_space(chars, i);
                match chars.get(i) {
                    Some('}') => return i + 1,
                    Some(',') => i += 1,
                    None => return i,
                    Some(_) => {
                        let before = i;
                        i = parse_tree(chars, i, &mut prefix.clone(), paths);
                        if i == before {
                            // Not a tree: skip the character rather than loop.
                            i += 1;
                        }
                    }
                }
            }
        }
        Some('*') => {
            paths.push(prefix.clone());
            i + 1
        }
        _ => match identifier(chars, i) {
            Some((name, end)) => {
                if name != "self" {
                    prefix.push(name);
                }
                let after = skip_space(chars, end);
                let nested = chars[after..].starts_with(&[':', ':'])
                    && matches!(
                        chars.get(skip_space(chars, after + 2)),
                        Some(c) if c.is_alphabetic() || *c == '_' || *c == '{' || *c == '*'
                    );
                if nested {
                    parse_tree(chars, after + 2, prefix, paths)
                } else {
                    paths.push(prefix.clone());
                    // A rename (`a as b`) names nothing more.
                    match identifier(chars, after) {
                        Some((word, end)) if word == "as" => {
                            identifier(chars, skip_space(chars, end)).map_or(end, |(_, end)| end)
                        }
                        _ => end,
                    }
                }
            }
            None => {
                if !prefix.is_empty() {
                    paths.push(prefix.clone());
                }
                i
            }
        },
    }
}

/// The module a path names: its longest prefix that is a module of `modules` (the crate
/// root if none is).
fn target(path: &[String], modules: &BTreeSet<String>) -> String {
    (1..=path.len())
        .rev()
        .map(|k| path[..k].join("::"))
        .find(|m| modules.contains(m))
        .unwrap_or_else(|| "crate".to_string())
}

/// Module → the modules it names (not itself), for the files of one crate. A path to an
/// item the crate root re-exports (`crate::Graph`, with `pub use graph::Graph;` in
/// `lib.rs`) names the module the item comes from.
fn dependencies(files: &[SourceFile]) -> BTreeMap<String, BTreeSet<String>> {
    let modules: BTreeSet<String> = files.iter().map(|f| f.module.clone()).collect();
    let reexported: BTreeMap<String, String> = files
        .iter()
        .filter(|f| f.module == "crate")
        .flat_map(|f| module_paths(&f.code, &[], &f.children))
        .filter_map(|p| Some((p.last()?.clone(), target(&p, &modules))))
        .filter(|(_, module)| module != "crate")
        .collect();
    let target = |p: &[String]| match target(p, &modules) {
        root if root == "crate" => p
            .first()
            .and_then(|item| reexported.get(item).cloned())
            .unwrap_or(root),
        module => module,
    };
    files
        .iter()
        .map(|f| {
            let own: Vec<String> = if f.module == "crate" {
                Vec::new()
            } else {
                f.module.split("::").map(String::from).collect()
            };
            let deps = module_paths(&f.code, &own, &f.children)
                .iter()
                .map(|p| target(p))
                .filter(|t| *t != f.module)
                .collect();
            (f.module.clone(), deps)
        })
        .collect()
}

/// The library files of the package in folder `package`.
fn library(package: &str) -> Vec<SourceFile> {
    let krate = crates()
        .into_iter()
        .find(|c| c.package == package && c.name.ends_with("(lib)"))
        .unwrap_or_else(|| panic!("the {package} crate"));
    assert!(
        krate.files.len() > 10,
        "found only {} files",
        krate.files.len()
    );
    krate.files
}

/// The orchestration library's files.
fn runtime() -> Vec<SourceFile> {
    library("runtime")
}

/// The transport library's files.
fn transport() -> Vec<SourceFile> {
    library("transport")
}

/// A cycle of `graph`, if it has one, as the modules along it (the first repeated last).
fn find_cycle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    #[derive(Clone, Copy, PartialEq)]
    enum Mark {
        Unseen,
        OnPath,
        Done,
    }
    fn visit(
        node: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        marks: &mut BTreeMap<String, Mark>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        marks.insert(node.to_string(), Mark::OnPath);
        path.push(node.to_string());
        for next in graph.get(node).into_iter().flatten() {
            match marks.get(next).copied().unwrap_or(Mark::Unseen) {
                Mark::OnPath => {
                    let start = path.iter().position(|m| m == next).unwrap();
                    let mut cycle = path[start..].to_vec();
                    cycle.push(next.clone());
                    return Some(cycle);
                }
                Mark::Unseen => {
                    if let Some(cycle) = visit(next, graph, marks, path) {
                        return Some(cycle);
                    }
                }
                Mark::Done => {}
            }
        }
        path.pop();
        marks.insert(node.to_string(), Mark::Done);
        None
    }
    let mut marks = BTreeMap::new();
    for node in graph.keys() {
        if marks.get(node).copied().unwrap_or(Mark::Unseen) == Mark::Unseen
            && let Some(cycle) = visit(node, graph, &mut marks, &mut Vec::new())
        {
            return Some(cycle);
        }
    }
    None
}

/// The transports: the top-level modules the registry in `transport/src/registry.rs` names,
/// from its lines `Variant => crate::MODULE::…::INFO,`. None may name another.
fn transports() -> &'static [String] {
    static MODULES: std::sync::OnceLock<Vec<String>> = std::sync::OnceLock::new();
    MODULES.get_or_init(read_transports)
}

fn read_transports() -> Vec<String> {
    let text = std::fs::read_to_string(root().join("transport/src/registry.rs")).unwrap();
    let code = code_only(&text);
    let start = code.find("transports! {").expect("the transport registry");
    let body = &code[start..start + code[start..].find('}').unwrap()];
    let modules: Vec<String> = body
        .lines()
        .filter_map(|line| {
            let path = line.split_once("=> crate::")?.1;
            Some(path.split("::").next()?.to_string())
        })
        .collect();
    assert!(modules.len() >= 5, "found only {modules:?}");
    modules
}

/// The transport a module belongs to, if any.
fn transport_of(module: &str) -> Option<String> {
    let top = module.split("::").next().unwrap_or(module);
    transports().iter().find(|t| *t == top).cloned()
}

#[test]
fn every_source_file_belongs_to_a_crate() {
    let reached: BTreeSet<PathBuf> = crates()
        .iter()
        .flat_map(|c| c.files.iter().map(|f| f.path.clone()))
        .collect();
    let mut orphans = Vec::new();
    for package in packages() {
        let mut stack = vec![root().join(package).join("src")];
        while let Some(dir) = stack.pop() {
            for entry in std::fs::read_dir(&dir).unwrap() {
                let path = entry.unwrap().path();
                if path.is_dir() {
                    stack.push(path);
                } else if path.extension().is_some_and(|e| e == "rs") && !reached.contains(&path) {
                    orphans.push(path.display().to_string());
                }
            }
        }
    }
    assert!(orphans.is_empty(), "files no `mod` reaches: {orphans:?}");
}

#[test]
fn no_import_cycle_in_any_crate() {
    let crates = crates();
    assert!(crates.len() >= 6, "found only {} crates", crates.len());
    for krate in crates {
        if let Some(cycle) = find_cycle(&dependencies(&krate.files)) {
            panic!("import cycle in {}: {}", krate.name, cycle.join(" -> "));
        }
    }
}

#[test]
fn no_transport_names_another() {
    let mut crossings = Vec::new();
    for (module, deps) in dependencies(&transport()) {
        let Some(own) = transport_of(&module) else {
            continue;
        };
        for dep in deps {
            if transport_of(&dep).is_some_and(|other| other != own) {
                crossings.push(format!("{module} -> {dep}"));
            }
        }
    }
    assert!(
        crossings.is_empty(),
        "transports naming another transport: {crossings:?}"
    );
}

/// The layer of a module in `layers` (0 is the top), `None` for the crate root, which only
/// declares the modules.
fn layer_of(module: &str, layers: &[&[&str]]) -> Option<usize> {
    let top = module.split("::").next().unwrap_or(module);
    if top == "crate" {
        return None;
    }
    let top = if transports().iter().any(|t| t == top) {
        TRANSPORT_MODULES
    } else {
        top
    };
    let layer = layers.iter().position(|layer| layer.contains(&top));
    assert!(
        layer.is_some(),
        "module {module} is in no layer: add it to its crate's layers"
    );
    layer
}

#[test]
fn no_module_names_a_higher_layer() {
    let mut upward = Vec::new();
    for (files, layers) in [(runtime(), RUNTIME_LAYERS), (transport(), TRANSPORT_LAYERS)] {
        for (module, deps) in dependencies(&files) {
            let Some(own) = layer_of(&module, layers) else {
                continue;
            };
            for dep in deps {
                if layer_of(&dep, layers).is_some_and(|other| other < own) {
                    upward.push(format!("{module} -> {dep}"));
                }
            }
        }
    }
    assert!(
        upward.is_empty(),
        "imports running up the layers: {upward:?}"
    );
}

#[test]
fn long_files_say_why() {
    let mut unexplained = Vec::new();
    for file in crates().into_iter().flat_map(|c| c.files) {
        let lines = file.text.lines().count();
        let reason = file
            .text
            .lines()
            .take_while(|l| l.starts_with("//!") || l.trim().is_empty())
            .any(|l| l.starts_with("//! Size:"));
        if lines > MAX_LINES && !reason {
            unexplained.push(format!("{} ({lines} lines)", file.path.display()));
        }
    }
    assert!(
        unexplained.is_empty(),
        "files above {MAX_LINES} lines without a `//! Size:` line in their module doc: {unexplained:?}"
    );
}

#[test]
fn the_parser_reads_nested_use_trees_and_skips_comments_and_strings() {
    let code = code_only(
        r##"
        use crate::{a, b::{c, d::*}, self as me};
        #[cfg(feature = "zenoh")]
        use crate::e::f::G;
        // use crate::commented::Out;
        /* use crate::block /* nested */ crate::still_comment */
        let s = "crate::in_a_string";
        let r = r#"crate::in_a_raw "string""#;
        let c = '"'; let l: &'static str = x;
        let v = crate::h::i::<u8>(crate::j::K);
        $crate::not_ours::X;
        "##,
    );
    let paths: Vec<String> = module_paths(&code, &[], &[])
        .iter()
        .map(|p| p.join("::"))
        .collect();
    assert_eq!(paths, ["a", "b::c", "b::d", "", "e::f::G", "h::i", "j::K"]);
    // Relative paths, seen from module `m::n` with a child `k` declared by `mod k;`.
    let code = code_only(
        r#"
        mod k;
        use super::sibling::X;
        use self::k::Y;
        fn f() { k::run(); other::k::no(); super::super::top(); }
        #[cfg(test)]
        mod tests {
            use super::*;
            fn g() { self::h(); }
        }
        "#,
    );
    assert_eq!(declared_modules(&code), ["k"]);
    let own = ["m".to_string(), "n".to_string()];
    let paths: Vec<String> = module_paths(&code, &own, &["k".to_string()])
        .iter()
        .map(|p| p.join("::"))
        .collect();
    assert_eq!(
        paths,
        ["m::sibling::X", "m::n::k::Y", "m::n::k::run", "top"]
    );
    let modules: BTreeSet<String> = ["a", "b", "b::d", "e", "h"]
        .into_iter()
        .map(String::from)
        .collect();
    let to = |p: &str| {
        target(
            &p.split("::").map(String::from).collect::<Vec<_>>(),
            &modules,
        )
    };
    assert_eq!(to("b::d::Thing"), "b::d");
    assert_eq!(to("e::f::G"), "e");
    assert_eq!(to("nowhere"), "crate");
    let graph: BTreeMap<String, BTreeSet<String>> = [
        ("a", vec!["b"]),
        ("b", vec!["c"]),
        ("c", vec!["a"]),
        ("d", vec![]),
    ]
    .into_iter()
    .map(|(m, deps)| (m.to_string(), deps.into_iter().map(String::from).collect()))
    .collect();
    assert_eq!(find_cycle(&graph).unwrap(), ["a", "b", "c", "a"]);
}

/// `code` with the bodies of `#[cfg(test)]` inline modules blanked (tests may name anything).
fn without_tests(code: &str) -> String {
    let mut chars: Vec<char> = code.chars().collect();
    let spans = inline_modules(&chars);
    let mut from = 0;
    while let Some(at) = find(&chars, from, "#[cfg(test)]") {
        from = at + 1;
        if let Some(&(start, end)) = spans.iter().find(|(start, _)| *start > at) {
            let between: String = chars[at + 12..start].iter().collect();
            if between.trim().is_empty() || between.trim().starts_with("#[") {
                for c in &mut chars[start..=end] {
                    if *c != '\n' {
                        *c = ' ';
                    }
                }
            }
        }
    }
    chars.into_iter().collect()
}

/// The registry's methods: `(Variant, module)` from the lines `Variant => module::INFO,`
/// of `agents/src/methods/mod.rs`.
fn registered_methods() -> Vec<(String, String)> {
    let text = std::fs::read_to_string(root().join("agents/src/methods/mod.rs")).unwrap();
    let code = code_only(&text);
    let start = code.find("registry! {").expect("the method registry");
    let body = &code[start..start + code[start..].find('}').unwrap()];
    let methods: Vec<(String, String)> = body
        .lines()
        .filter_map(|line| {
            let (variant, info) = line.split_once("=>")?;
            let module = info.trim().split("::").next()?.to_string();
            Some((variant.trim().to_string(), module))
        })
        .collect();
    assert!(methods.len() >= 5, "found only {methods:?}");
    methods
}

/// Whether `code` names `word` as a whole identifier path segment.
fn names(code: &str, word: &str) -> bool {
    let chars: Vec<char> = code.chars().collect();
    let mut from = 0;
    while let Some(at) = find(&chars, from, word) {
        from = at + 1;
        let before = at.checked_sub(1).map(|p| chars[p]);
        let after = chars.get(at + word.chars().count()).copied();
        let part = |c: Option<char>| c.is_some_and(|c| c.is_alphanumeric() || c == '_');
        if !part(before) && !part(after) {
            return true;
        }
    }
    false
}

#[test]
fn the_runtime_and_the_benchmarks_name_no_concrete_method() {
    let methods = registered_methods();
    let mut named = Vec::new();
    for krate in crates()
        .into_iter()
        .filter(|c| ["runtime", "transport", "bench"].contains(&c.package.as_str()))
    {
        for file in &krate.files {
            let code = without_tests(&file.code);
            for (variant, module) in &methods {
                for word in [format!("Method::{variant}"), format!("methods::{module}")] {
                    if names(&code, &word) {
                        named.push(format!("{}: {word}", file.path.display()));
                    }
                }
            }
        }
    }
    assert!(named.is_empty(), "concrete methods named: {named:?}");
}

#[test]
fn process_orchestration_names_no_concrete_transport() {
    let mut named = Vec::new();
    // Within the runtime, `process` names no module of another crate by `crate::…`; its
    // names of the transport crate are checked on its code below.
    for (module, deps) in dependencies(&runtime()) {
        if module.split("::").next() != Some("process") {
            continue;
        }
        for dep in deps {
            if transport_of(&dep).is_some() {
                named.push(format!("{module} -> {dep}"));
            }
        }
    }
    let variants = ["Sim", "Threads", "Shm", "Ipc", "Uds", "Zenoh"];
    for file in runtime()
        .iter()
        .filter(|f| f.module.split("::").next() == Some("process"))
    {
        let code = without_tests(&file.code);
        for variant in variants {
            if names(&code, &format!("Transport::{variant}")) {
                named.push(format!("{}: Transport::{variant}", file.path.display()));
            }
        }
        for module in transports() {
            if names(&code, &format!("admm_ta_transport::{module}")) {
                named.push(format!(
                    "{}: admm_ta_transport::{module}",
                    file.path.display()
                ));
            }
        }
    }
    assert!(
        named.is_empty(),
        "the process orchestration names concrete transports: {named:?}"
    );
}

/// The `Result<…>` types in `code` whose error type is `String`.
fn string_results(code: &str) -> Vec<String> {
    let chars: Vec<char> = code.chars().collect();
    let mut found = Vec::new();
    let mut from = 0;
    while let Some(at) = find(&chars, from, "Result<") {
        from = at + 1;
        if at > 0 && (chars[at - 1].is_alphanumeric() || chars[at - 1] == '_') {
            continue;
        }
        let (mut depth, mut args, mut current) = (0, Vec::new(), String::new());
        for (k, &c) in chars.iter().enumerate().skip(at + 6) {
            match c {
                '<' => depth += 1,
                '>' if k > 0 && chars[k - 1] == '-' => {}
                '>' => depth -= 1,
                ',' if depth == 1 => {
                    args.push(std::mem::take(&mut current));
                    continue;
                }
                _ => {}
            }
            if depth == 0 {
                args.push(std::mem::take(&mut current));
                break;
            }
            if !(depth == 1 && c == '<') {
                current.push(c);
            }
        }
        if args.len() == 2 && args[1].trim() == "String" {
            found.push(chars[at..at + 40.min(chars.len() - at)].iter().collect());
        }
    }
    if names(code, "type Err = String") {
        found.push("type Err = String".into());
    }
    found
}

#[test]
fn the_runtime_and_the_agents_return_no_string_errors() {
    assert_eq!(
        string_results("fn f() -> Result<Vec<u8>, String> { g::<Result<(), E>>() }").len(),
        1
    );
    assert!(string_results("fn f() -> Result<String, E> {}").is_empty());
    let mut found = Vec::new();
    for krate in crates()
        .into_iter()
        .filter(|c| ["runtime", "transport", "agents"].contains(&c.package.as_str()))
    {
        for file in &krate.files {
            for result in string_results(&without_tests(&file.code)) {
                found.push(format!("{}: {result}", file.path.display()));
            }
        }
    }
    assert!(found.is_empty(), "errors as strings: {found:?}");
}

#[test]
fn every_transport_is_a_folder_of_the_same_shape() {
    let mut missing = Vec::new();
    for module in transports() {
        let folder = root().join("transport/src").join(module);
        for file in TRANSPORT_FILES {
            if !folder.join(file).is_file() {
                missing.push(format!("{module}/{file}"));
            }
        }
        let declares = std::fs::read_to_string(folder.join("mod.rs"))
            .is_ok_and(|text| names(&code_only(&text), "pub const INFO"));
        if !declares {
            missing.push(format!("{module}/mod.rs: its `pub const INFO`"));
        }
    }
    assert!(missing.is_empty(), "transport folders missing: {missing:?}");
}

#[test]
fn the_transport_crate_does_not_depend_on_the_orchestration() {
    let manifest = std::fs::read_to_string(root().join("transport/Cargo.toml")).unwrap();
    assert!(
        !manifest.contains("admm-ta-runtime") && !manifest.contains("admm-ta ="),
        "transport/Cargo.toml names a crate above it"
    );
    let mut named = Vec::new();
    for file in transport() {
        if names(&file.code, "admm_ta_runtime") {
            named.push(file.path.display().to_string());
        }
    }
    assert!(
        named.is_empty(),
        "transport files naming the runtime: {named:?}"
    );
}
