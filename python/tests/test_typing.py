"""The type stubs and annotations: the extension module's stub agrees with the module
(mypy's stubtest), and the package type-checks strictly."""

import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
PACKAGE = os.path.join(os.path.dirname(HERE), "admm_ta")


def run(*args):
    # From the tests' folder: the installed package, not the source folder (which has no
    # extension module in a fresh clone).
    return subprocess.run([sys.executable, "-m", *args], capture_output=True, text=True,
                          cwd=HERE, timeout=300)


def test_the_stub_agrees_with_the_extension_module():
    out = run("mypy.stubtest", "admm_ta._core")
    assert out.returncode == 0, out.stdout + out.stderr


def test_the_package_type_checks_strictly():
    out = run("mypy", "--strict", "--no-incremental", PACKAGE)
    assert out.returncode == 0, out.stdout + out.stderr


def test_the_package_is_marked_typed():
    assert os.path.exists(os.path.join(PACKAGE, "py.typed"))
