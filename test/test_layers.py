# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The package's imports, read with ``ast``: no circle, down the layers only, no private name.

Every import of every module under ``mpi_ros/`` counts, at any depth (lazy imports in
functions, ``TYPE_CHECKING`` blocks).  The layers are read from the table in
``docs/design.md`` ("Import layers"), so the map and the check cannot drift apart: a module
may import modules of its own layer and of the layers listed before it.
"""

import ast
from pathlib import Path
import re

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / 'mpi_ros'
DESIGN = ROOT / 'docs' / 'design.md'


def _modules():
    """Return {dotted name: path} of every module of the package (packages by __init__)."""
    found = {}
    for path in PACKAGE.rglob('*.py'):
        parts = ('mpi_ros',) + path.relative_to(PACKAGE).with_suffix('').parts
        if parts[-1] == '__init__':
            parts = parts[:-1]
        found['.'.join(parts)] = path
    return found


MODULES = _modules()


def _base(name, path, level):
    # The package a relative import of `level` dots starts from.
    package = name.split('.') if path.name == '__init__.py' else name.split('.')[:-1]
    return package[:len(package) - level + 1]


def _imports(name, path):
    """
    Yield (line, target module, imported name or None) for each import of the package.

    ``from X import y`` yields the module ``X.y`` when it is one (name None), else ``X``
    with the name ``y``.
    """
    tree = ast.parse(path.read_text(), filename=str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split('.')[0] == 'mpi_ros':
                    yield node.lineno, alias.name, None
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                module = '.'.join(_base(name, path, node.level)
                                  + ([node.module] if node.module else []))
            else:
                module = node.module or ''
            if module.split('.')[0] != 'mpi_ros':
                continue
            for alias in node.names:
                sub = f'{module}.{alias.name}'
                if sub in MODULES:
                    yield node.lineno, sub, None
                else:
                    yield node.lineno, module, alias.name


def _module_aliases(name, path):
    # Local names bound to a module of the package (`from . import qp`, `import x as m`).
    tree = ast.parse(path.read_text(), filename=str(path))
    aliases = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split('.')[0] == 'mpi_ros':
                    aliases.add(alias.asname or alias.name.split('.')[0])
        elif isinstance(node, ast.ImportFrom):
            module = ('.'.join(_base(name, path, node.level)
                               + ([node.module] if node.module else []))
                      if node.level else node.module or '')
            for alias in node.names:
                if f'{module}.{alias.name}' in MODULES:
                    aliases.add(alias.asname or alias.name)
    return tree, aliases


def _edges():
    """Return {module: {imported module: first line}} (the module itself left out)."""
    edges = {}
    for name, path in MODULES.items():
        out = edges.setdefault(name, {})
        for line, target, _ in _imports(name, path):
            if target != name and target in MODULES:
                out.setdefault(target, line)
    return edges


def _private(part):
    return part.startswith('_') and not (part.startswith('__') and part.endswith('__'))


def _cycles(edges):
    """Return the strongly connected components of more than one module (Tarjan, iterative)."""
    index, low, on_stack, stack, found = {}, {}, set(), [], []
    counter = 0
    for root in sorted(edges):
        if root in index:
            continue
        work = [(root, iter(sorted(edges[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(edges.get(child, {})))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(sorted(component))
    return found


def _layers():
    """Return [(layer name, [entries])] from design.md's "Import layers" table, in order."""
    text = DESIGN.read_text()
    start = text.index('## Import layers')
    rows = []
    for line in text[start:].splitlines()[1:]:
        if line.startswith('## '):
            break
        cells = [c.strip() for c in line.strip().strip('|').split('|')]
        if len(cells) == 2 and re.match(r'^\d+\.', cells[0]):
            rows.append((cells[0], re.findall(r'`([^`]+)`', cells[1])))
    return rows


def _layer_of(module, layers):
    # The rank of the most specific entry that holds the module.
    path = MODULES[module].relative_to(PACKAGE).as_posix()
    best = None
    for rank, (_, entries) in enumerate(layers):
        for entry in entries:
            holds = (path.startswith(entry) if entry.endswith('/') else path == entry)
            if holds and (best is None or len(entry) > best[1]):
                best = (rank, len(entry))
    return None if best is None else best[0]


def test_the_package_is_found():
    # The scan sees the whole package, sub-packages and lazy imports included.
    assert len(MODULES) > 80, sorted(MODULES)
    assert 'mpi_ros.identification.fitter' in MODULES
    edges = _edges()
    assert 'mpi_ros.extensions.resonance' in edges['mpi_ros.model_fit']
    # A lazy import inside a function counts (here the application's import of the
    # diagnose command, made when the subcommand runs).
    assert 'mpi_ros.app.diagnose_cli' in edges['mpi_ros.app.cli']


def test_no_import_circle():
    circles = _cycles(_edges())
    assert not circles, '\n'.join(' <-> '.join(c) for c in circles)


def test_the_cycle_finder_finds_a_circle():
    # The check itself: a circle of three modules and a self-contained tail.
    edges = {'a': {'b': 1}, 'b': {'c': 1}, 'c': {'a': 1, 'd': 1}, 'd': {}}
    assert _cycles(edges) == [['a', 'b', 'c']]
    assert _cycles({'a': {'b': 1}, 'b': {}}) == []


def test_every_module_has_a_layer():
    layers = _layers()
    assert len(layers) >= 8, layers
    missing = sorted(m for m in MODULES if _layer_of(m, layers) is None)
    assert not missing, ('modules in no layer of docs/design.md ("Import layers"): '
                         + ', '.join(missing))


def test_imports_run_down_the_layers():
    layers = _layers()
    up = []
    for module, targets in _edges().items():
        mine = _layer_of(module, layers)
        for target, line in targets.items():
            theirs = _layer_of(target, layers)
            if mine is not None and theirs is not None and theirs > mine:
                up.append(f'{MODULES[module].relative_to(ROOT)}:{line} ({layers[mine][0]})'
                          f' imports {target} ({layers[theirs][0]})')
    assert not up, '\n'.join(sorted(up))


@pytest.mark.parametrize('module, target, expected', [
    ('mpi_ros.identification.fitter', 'mpi_ros.extensions.resonance', True),
    ('mpi_ros.model_fit', 'mpi_ros.extensions.resonance', False),
    ('mpi_ros.plant.simulator', 'mpi_ros.diagnosis.signatures', True),
    ('mpi_ros.diagnosis.diagnose', 'mpi_ros.app.cli_options', True),
    ('mpi_ros.operators.model', 'mpi_ros.errors', False),
])
def test_the_layer_order_tells_up_from_down(module, target, expected):
    # The back-arrows this check was written against would be caught.
    layers = _layers()
    assert (_layer_of(target, layers) > _layer_of(module, layers)) == expected


def test_no_private_name_is_imported_from_another_module():
    found = []
    for name, path in sorted(MODULES.items()):
        where = path.relative_to(ROOT)
        for line, target, imported in _imports(name, path):
            if any(_private(part) for part in target.split('.')):
                found.append(f'{where}:{line} imports the private module {target}')
            elif imported is not None and _private(imported) and target != name:
                found.append(f'{where}:{line} imports {target}.{imported}')
        tree, aliases = _module_aliases(name, path)
        for node in ast.walk(tree):
            if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
                    and node.value.id in aliases and _private(node.attr)):
                found.append(f'{where}:{node.lineno} reads {node.value.id}.{node.attr}')
    assert not found, '\n'.join(found)
