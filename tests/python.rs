//! The Python package (`python/`): builds and installs it into a virtual environment of its
//! own, made here from the package registries (numpy, scipy, pytest, mypy, maturin), and
//! runs its pytest suite — scipy as the oracle of `linear_sum_assignment`, `solve` over
//! every method and transport, Ctrl-C, the type stubs — and the docstrings' examples.
//!
//! So the README's one test command (`cargo test --workspace --features zenoh`) runs the
//! Python tests too. The environment lives in `target/tmp/python-venv` and the extension
//! builds in `target/python` (not cargo's own target directory, which `cargo test` holds
//! locked while tests run); both are reused by later runs. Needs `python3` (3.9 or newer)
//! with `venv`: without one the test says so and passes, except under CI (`CI=true`),
//! where it fails.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The test dependencies, with the build backend (built without isolation, so offline
/// reruns need nothing new).
const REQUIREMENTS: [&str; 6] = [
    "numpy>=1.21",
    "scipy>=1.9",
    "pytest>=7",
    "mypy>=1.8",
    "maturin>=1.9,<2",
    "pip>=23",
];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn run(command: &mut Command, what: &str) {
    let status = command
        .status()
        .unwrap_or_else(|e| panic!("{what}: cannot start: {e}"));
    assert!(status.success(), "{what} failed: {status}");
}

/// `python3`, if it is there and new enough.
fn system_python() -> Option<PathBuf> {
    let ok = Command::new("python3")
        .args([
            "-c",
            "import sys, venv; sys.exit(0 if sys.version_info >= (3, 9) else 1)",
        ])
        .status()
        .is_ok_and(|s| s.success());
    ok.then(|| PathBuf::from("python3"))
}

/// The virtual environment with the test dependencies (made once, then reused).
fn environment(python: &Path) -> PathBuf {
    let venv = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("python-venv");
    let bin = venv.join("bin").join("python");
    if !bin.exists() {
        run(
            Command::new(python).args(["-m", "venv"]).arg(&venv),
            "python3 -m venv",
        );
    }
    run(
        pip_install(&bin).args(REQUIREMENTS),
        "pip install (the test dependencies)",
    );
    bin
}

/// `python -m pip install`, quietly.
fn pip_install(python: &Path) -> Command {
    let mut command = Command::new(python);
    command.args([
        "-m",
        "pip",
        "install",
        "--quiet",
        "--disable-pip-version-check",
    ]);
    command
}

/// `PATH` with the environment's `bin` first (the build backend runs `maturin` from it).
fn with_venv_bin(venv_python: &Path) -> std::ffi::OsString {
    let bin = venv_python.parent().expect("bin/python").to_path_buf();
    let rest = std::env::var_os("PATH").unwrap_or_default();
    std::env::join_paths(std::iter::once(bin).chain(std::env::split_paths(&rest)))
        .expect("PATH entries without ':'")
}

#[test]
fn the_python_package_passes_its_tests() {
    let Some(python) = system_python() else {
        let message =
            "python3 (3.9 or newer, with venv) is not on PATH: the Python package is not tested";
        assert!(std::env::var("CI").is_err(), "{message}");
        eprintln!("skipped: {message}");
        return;
    };
    let venv_python = environment(&python);
    let target = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .parent()
        .expect("target/tmp is in the target directory")
        .join("python");
    // The README's install line, without build isolation (the backend is installed above).
    run(
        pip_install(&venv_python)
            .args(["--no-build-isolation", "--force-reinstall", "--no-deps"])
            .args(["--config-settings", "build-args=--locked"])
            .arg(root().join("python"))
            .env("CARGO_TARGET_DIR", &target)
            .env("PATH", with_venv_bin(&venv_python)),
        "pip install ./python",
    );
    // The installed package, not the source folder: run from the tests' folder with
    // importlib imports, so `admm_ta` resolves to site-packages.
    run(
        Command::new(&venv_python)
            .args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
            .arg(root().join("python").join("tests"))
            .current_dir(root().join("python").join("tests")),
        "pytest python/tests",
    );
    // The docstrings' examples, on the installed modules.
    let site = Command::new(&venv_python)
        .args([
            "-c",
            "import admm_ta, os; print(os.path.dirname(admm_ta.__file__))",
        ])
        .output()
        .expect("python runs");
    assert!(site.status.success());
    let package = String::from_utf8(site.stdout)
        .expect("a path")
        .trim()
        .to_string();
    assert!(
        !package.starts_with(root().join("python").to_str().unwrap()),
        "the tests must run the installed package, not {package}"
    );
    run(
        Command::new(&venv_python)
            .args([
                "-m",
                "pytest",
                "-q",
                "-p",
                "no:cacheprovider",
                "--doctest-modules",
            ])
            .args(["--ignore", &format!("{package}/__main__.py")])
            .arg(&package)
            .current_dir(root().join("python").join("tests")),
        "the docstrings' examples",
    );
}
