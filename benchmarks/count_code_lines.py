# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
Count the code lines of the package's folders (issue 19: ``nodes/`` against ``compensation/``).

A code line is a line that holds a token other than a comment and is not part of a
docstring (the first string statement of a module, class or function).  Blank lines,
comments and docstrings do not count; a line with code and a trailing comment does.

Run: ``python benchmarks/count_code_lines.py [FOLDER ...]`` (default: every folder of
``mpi_ros/`` and the package root); prints one line per folder and exits 0.
"""

import ast
import io
from pathlib import Path
import sys
import tokenize
from typing import List, Set

__all__ = ['code_lines', 'folder_code_lines', 'main']

_PACKAGE = Path(__file__).resolve().parent.parent / 'mpi_ros'
_SKIPPED = {tokenize.COMMENT, tokenize.NL, tokenize.NEWLINE, tokenize.INDENT,
            tokenize.DEDENT, tokenize.ENCODING, tokenize.ENDMARKER}


def _docstring_lines(tree: ast.AST) -> Set[int]:
    """Return the line numbers covered by the docstrings of a module's tree."""
    lines: Set[int] = set()
    for node in ast.walk(tree):
        if not isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef,
                                 ast.AsyncFunctionDef)):
            continue
        body = node.body
        if (body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant)
                and isinstance(body[0].value.value, str)):
            first = body[0]
            last = first.end_lineno if first.end_lineno is not None else first.lineno
            lines.update(range(first.lineno, last + 1))
    return lines


def code_lines(source: str) -> int:
    r"""
    Count the code lines of one Python source.

    Parameters
    ----------
    source : str
        The text of a module.

    Returns
    -------
    int
        Lines holding code: not blank, not only a comment, not in a docstring.

    Examples
    --------
    >>> code_lines("'''Doc.'''\\n\\n# note\\nx = 1  # one\\n")
    1

    """
    docstrings = _docstring_lines(ast.parse(source))
    lines: Set[int] = set()
    for token in tokenize.generate_tokens(io.StringIO(source).readline):
        if token.type in _SKIPPED:
            continue
        lines.update(range(token.start[0], token.end[0] + 1))
    return len(lines - docstrings)


def folder_code_lines(folder: Path) -> int:
    """
    Count the code lines of every ``.py`` file directly in ``folder`` (not below it).

    Parameters
    ----------
    folder : pathlib.Path
        A package folder.

    Returns
    -------
    int
        The sum of :func:`code_lines` over its modules.

    """
    return sum(code_lines(path.read_text(encoding='utf-8'))
               for path in sorted(folder.glob('*.py')))


def main(argv: List[str]) -> int:
    """
    Print the code lines of each folder given (default: every folder of the package).

    Parameters
    ----------
    argv : list of str
        Folders, relative to ``mpi_ros/`` or absolute.

    Returns
    -------
    int
        0.

    """
    folders = [_PACKAGE / name for name in argv] if argv else (
        [_PACKAGE] + sorted(p for p in _PACKAGE.iterdir()
                            if p.is_dir() and (p / '__init__.py').exists()))
    for folder in folders:
        name = folder.relative_to(_PACKAGE.parent) if folder.is_relative_to(
            _PACKAGE.parent) else folder
        print(f'{folder_code_lines(folder):6d} code lines  {name}/')
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
