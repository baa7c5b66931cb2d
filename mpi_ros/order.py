# Copyright 2026 The mpi_ros authors. Licensed under the Apache License, Version 2.0.
"""
The model order (n, l) as the user writes it: ``auto``, ``N,L`` or ``N L``.

n is the number of play operators of H (5), l the number of dead-zone
operators of S (18). The command line (``--order``) and the identifier node
(``order``) parse it with the one function :func:`parse_order`.
"""

from __future__ import annotations

import re
from typing import Sequence, Union

from .errors import IdentificationError

__all__ = ['Order', 'parse_order', 'format_order']

#: ``'auto'`` or ``(n, l)``.
Order = Union[str, tuple[int, int]]

_WHOLE = re.compile(r'\d+')


def parse_order(value: str | Sequence[str], *, option: str = 'order') -> Order:
    """
    Parse a model order written as ``auto``, ``N,L`` or ``N L``.

    Parameters
    ----------
    value : str or sequence of str
        The text, or the command-line words after the option (``['14', '7']``,
        ``['14,7']``, ``['auto']``); words are joined by a blank.
    option : str, optional
        The option as the user wrote it (``--order``, ``order``), for the
        message.

    Returns
    -------
    'auto' or tuple of (int, int)
        ``'auto'`` (order selection by the fit errors) or ``(n, l)`` with
        n, l >= 1.

    Raises
    ------
    IdentificationError
        For anything else; the message names `option` and shows the value.

    Examples
    --------
    >>> parse_order('auto'), parse_order('14,7'), parse_order(['14', '7'])
    ('auto', (14, 7), (14, 7))

    """
    text = value if isinstance(value, str) else ' '.join(str(word) for word in value)
    cleaned = text.strip().lower()
    if cleaned == 'auto':
        return 'auto'
    parts = cleaned.replace(',', ' ').split()
    if len(parts) == 2 and all(_WHOLE.fullmatch(part) for part in parts):
        n, l_s = int(parts[0]), int(parts[1])
        if n >= 1 and l_s >= 1:
            return (n, l_s)
    msg = (f"{option} takes 'auto' or two whole numbers N, L >= 1 written N,L or N L "
           f'(e.g. 14,7); found {text!r}; the order must be N play operators and L '
           "dead-zone operators, or 'auto' to choose them by the fit errors")
    raise IdentificationError(msg)


def format_order(order: Order) -> str:
    """
    Describe an order for progress messages.

    Parameters
    ----------
    order : 'auto' or tuple of (int, int)
        A parsed order.

    Returns
    -------
    str
        ``'auto'`` or ``'n=N, l=L'``.

    """
    if isinstance(order, str):
        return order
    return f'n={order[0]}, l={order[1]}'
