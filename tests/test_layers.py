"""The package's layers: every import inside sweep (at module level or inside a
function) points down or sideways within a layer, never up, and there is no circle.

    cli -> maps, accuracy, map_precision, plot, toml_spec, distributed, diskspace
        -> engine -> execution, io
        -> kernels, grid, stability -> physics, methods, observables -> _config, ...

The documentation's layout section (docs/guide/extending.md) draws the same picture.
"""

import ast
from pathlib import Path

import pytest

import sweep

ROOT = Path(sweep.__file__).parent

#: Layer of each module (by name prefix, longest match wins); higher imports lower.
LAYERS = {
    "sweep._config": 0, "sweep._validate": 0, "sweep._version": 0, "sweep._timesteps": 0,
    "sweep._moved": 0,
    "sweep.strobe_phase": 0,  # a catalogue's drive phase: numpy and sweep._timesteps
    "sweep.catalogue_scene": 0,  # a catalogue's scene: numpy and json
    "sweep._known": 1,  # the known-cells rule reads the hits of sweep.observables
    "sweep.physics": 1, "sweep.methods": 1, "sweep.observables": 1,
    "sweep.system_observables": 1,
    "sweep.system_attractors": 1,  # a system's catalogue as arrays: numpy alone
    "sweep.catalogue_drives": 1,  # a catalogue's other drives: sweep.physics' effects
    "sweep.kernels": 2, "sweep.grid": 2, "sweep.stability": 2,
    "sweep.execution": 3, "sweep.io": 3, "sweep.settings": 3,
    "sweep.engine": 4, "sweep.engine_systems": 4,
    "sweep.maps": 5, "sweep.accuracy": 5, "sweep.map_precision": 5, "sweep.plot": 5,
    "sweep.toml_spec": 5, "sweep.toml_declared": 5, "sweep.toml_effects": 5,
    "sweep.toml_pilot": 5, "sweep.toml_periods": 5,
    "sweep.distributed": 5, "sweep.diskspace": 5,
    "sweep.cli": 6, "sweep.__main__": 7,
    "sweep.explore": 6,  # the browser explorer, beside cli: the public API and maps
    # deprecated shims at the 0.1 module paths (removed in 0.3): each sits in the layer
    # of the module it forwards to
    "sweep.metrics": 5, "sweep.response": 5, "sweep.scene": 1, "sweep.checkpoint": 3,
}


def _modules() -> dict[str, Path]:
    found = {}
    for path in ROOT.rglob("*.py"):
        parts = ("sweep",) + path.relative_to(ROOT).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        found[".".join(parts)] = path
    return found


MODULES = _modules()


def _layer(module: str) -> int:
    best = max((prefix for prefix in LAYERS
                if module == prefix or module.startswith(prefix + ".")), key=len)
    return LAYERS[best]


def _resolve(name: str) -> str:
    """The module ``name`` refers to: itself if it is one, else its package."""
    while name not in MODULES:
        name = name.rsplit(".", 1)[0]
    return name


def _imports(module: str) -> set[str]:
    """The sweep modules ``module`` imports, anywhere in its text."""
    path = MODULES[module]
    package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                base = f"{base}.{node.module}" if node.module else base
            else:
                base = node.module
            names = [f"{base}.{alias.name}" for alias in node.names]
        else:
            continue
        found.update(_resolve(name) for name in names if name.split(".")[0] == "sweep")
    return found - {module}


GRAPH = {module: _imports(module) for module in MODULES if module != "sweep"}


def test_every_module_has_a_layer():
    assert all(any(m == p or m.startswith(p + ".") for p in LAYERS) for m in GRAPH)


@pytest.mark.parametrize("module", sorted(GRAPH))
def test_imports_point_down(module):
    up = sorted(target for target in GRAPH[module]
                if target == "sweep" or _layer(target) > _layer(module))
    assert not up, f"{module} (layer {_layer(module)}) imports upward: {up}"


def test_no_import_circle():
    state = {}

    def visit(module, path):
        state[module] = "open"
        for target in GRAPH.get(module, ()):
            if state.get(target) == "open":
                raise AssertionError("import circle: " + " -> ".join(path + [target]))
            if target not in state:
                visit(target, path + [target])
        state[module] = "done"

    for module in sorted(GRAPH):
        if module not in state:
            visit(module, [module])
