"""``python -m sweep``: the same as the ``sweep`` command."""

from .cli import main

if __name__ == "__main__":
    raise SystemExit(main())
