"""The built-in systems' derivations, shipped with sweep so that they need no SymPy.

`sweep.physics.derive.derive` looks for a declaration here first, then in the disk
cache beside the kernels, and derives it with SymPy only when neither holds it. The
files are the disk cache's (``system_<key>.json``, the same key: the declaration's
``repr``, the ``jacobian`` flag and `sweep.physics.derive.DERIVE_VERSION`), so a file
that no longer matches (a new `DERIVE_VERSION`, a changed declaration) is never read,
only missed. ``tests/test_systems_shipped.py`` checks that every file equals a fresh
derivation and that the folder holds exactly the `built_ins`' files; after a change to
the derivation or to a built-in declaration, write them again with::

    python -m sweep.physics.shipped
"""

from __future__ import annotations

from pathlib import Path

from .derive import SHIPPED_FOLDER
from .system import SystemDeclaration
from .systems import COUPLINGS, coupled_pendula, double_pendulum

__all__ = ["FOLDER", "built_ins", "path_of", "write"]

#: The folder of the shipped derivations (package data), where `derive` looks first.
FOLDER = SHIPPED_FOLDER


def built_ins() -> list[tuple[SystemDeclaration, bool]]:
    """The declarations shipped, each with and without its Jacobian: the double pendulum
    with and without joint damping and a driven pivot, and coupled pendula of 2 to 4
    (chains) and 3 to 4 (rings) with either coupling. Larger ``n`` is derived on first
    use (SymPy).

    Returns
    -------
    list of (SystemDeclaration, bool)
        ``(declaration, jacobian)`` pairs, 28 of them.
    """
    declarations = [double_pendulum(damping=damping, pivot=pivot)
                    for damping in (False, True) for pivot in (False, True)]
    for coupling in COUPLINGS:
        declarations += [coupled_pendula(n, coupling, "chain") for n in (2, 3, 4)]
        declarations += [coupled_pendula(n, coupling, "ring") for n in (3, 4)]
    return [(declaration, jacobian) for declaration in declarations
            for jacobian in (False, True)]


def path_of(declaration: SystemDeclaration, jacobian: bool, folder: Path = FOLDER) -> Path:
    """Where ``declaration``'s derivation is shipped (whether or not it is there).

    Parameters
    ----------
    declaration : SystemDeclaration
    jacobian : bool
    folder : pathlib.Path, default `FOLDER`

    Returns
    -------
    pathlib.Path
    """
    from .derive import _key

    return folder / f"system_{_key(declaration, bool(jacobian))}.json"


def write(folder: Path = FOLDER) -> list[Path]:
    """Derive every `built_ins` declaration (SymPy) and write its file into ``folder``,
    removing the folder's other ``system_*.json`` files (stale derivations).

    Parameters
    ----------
    folder : pathlib.Path, default `FOLDER`

    Returns
    -------
    list of pathlib.Path
        The files written, in `built_ins` order.
    """
    from .derive import _derive_now, _write

    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for declaration, jacobian in built_ins():
        path = path_of(declaration, jacobian, folder)
        _write(path, declaration, jacobian, _derive_now(declaration, jacobian))
        written.append(path)
    for stale in set(folder.glob("system_*.json")) - set(written):
        stale.unlink()
    return written


if __name__ == "__main__":  # pragma: no cover - python -m sweep.physics.shipped
    for path in write():
        print(f"wrote {path}")
