"""A system's effects in a run file: the ``[system.<effect>]`` tables of `sweep.toml_spec`
and `sweep.toml_declared`, read (`system_effects`) and written back
(`system_effects_lines`, for the explorer's run files)."""

from __future__ import annotations

from ._validate import check_keys

__all__ = ["system_effects", "system_effects_lines"]


def system_effects(arguments: dict, effects: dict) -> tuple:
    """The effects of ``[system]`` (popped from ``arguments``): each ``[system.<name>]``
    a table of the effect's arguments (``on`` among them), or ``[[system.<name>]]`` an
    array of such tables (one per coordinate)."""
    found = []
    for name, cls in effects.items():
        if name not in arguments:
            continue
        value = arguments.pop(name)
        keys = [p.field for p in cls.declaration.parameters] + ["on"]
        accepted = (f"a table [system.{name}] with {', '.join(keys)} (on: a coordinate's "
                    f"name" + (", or none for the mass-proportional damping with "
                               "coefficient = c in 1/s" if name == "damping" else "")
                    + f"), or an array of them [[system.{name}]]")
        for entry in value if isinstance(value, list) else [value]:
            if not isinstance(entry, dict):
                raise TypeError(f"{name} must be {accepted}, got {entry!r}")
            check_keys(entry, keys, f" in [system.{name}]")
            found.append(cls(**entry))
    return tuple(found)


def system_effects_lines(effects: tuple, value_text) -> list[str]:
    """The run file's ``[system.<effect>]`` tables of a system's ``effects`` (as
    `system_effects` reads them): one per effect with its fields (``on`` where given),
    ``[[system.<effect>]]`` where an effect kind appears more than once; ``value_text``
    writes a value in TOML."""
    import dataclasses

    kinds = [type(e).declaration.name for e in effects]
    lines = []
    for effect, name in zip(effects, kinds):
        lines += ["", f"[[system.{name}]]" if kinds.count(name) > 1 else f"[system.{name}]"]
        lines += [f"{f.name} = {value_text(getattr(effect, f.name))}"
                  for f in dataclasses.fields(effect) if getattr(effect, f.name) is not None]
    return lines
