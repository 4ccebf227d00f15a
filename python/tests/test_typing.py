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


def test_no_import_circle_in_the_package():
    """No module of the package imports another that imports it back (annotations-only
    imports included), directly or around a circle."""
    import ast

    graph = {}
    for name in os.listdir(PACKAGE):
        if not name.endswith(".py"):
            continue
        module = name[:-3]
        tree = ast.parse(open(os.path.join(PACKAGE, name)).read())
        deps = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.level == 1:
                if node.module:
                    deps.add(node.module.split(".")[0])
                else:
                    deps.update(alias.name for alias in node.names)
        graph[module] = deps & {n[:-3] for n in os.listdir(PACKAGE) if n.endswith(".py")}

    def visit(module, path):
        assert module not in path, "import circle: " + " -> ".join(path + [module])
        for dep in graph.get(module, ()):
            visit(dep, path + [module])

    for module in graph:
        visit(module, [])
