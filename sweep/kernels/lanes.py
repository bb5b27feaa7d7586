"""Lanes of a block: per-trajectory code inside the kernels' blocks of SIMD lanes
(fixed-step, refill and adaptive), with per-lane state in small arrays
``lane_<name>``."""

from __future__ import annotations

import re
import textwrap

__all__ = ["ADAPTIVE_ARGUMENTS", "ASSIGNED", "BIND", "FIXED_ARGUMENTS", "IDENTIFIER",
           "KNOWN_ARGUMENTS", "allocate", "block_multiple", "blocks_head", "indent",
           "lane_loop", "lane_snippet", "scalar_lanes", "skip_unless"]

IDENTIFIER = re.compile(r"\b[A-Za-z_]\w*\b")
ASSIGNED = re.compile(r"^\s*([A-Za-z_]\w*)\s*(?:[-+*/]?=)(?!=)", re.MULTILINE)


def lane_snippet(code: str) -> str:
    """A per-trajectory snippet inside a block: ``out[i, ...]`` becomes the block's
    row buffer ``obuf[j, ...]`` (padding lanes then write nowhere shared)."""
    return code.replace("out[i,", "obuf[j,")


def lane_loop(body: str, lane: dict[str, str], *, level: int, head: str = "",
              stores: list[str] | None = None, count: str = "BLOCK",
              load: bool = True) -> str:
    """``for j in range(count):`` around ``body``: loads each lane variable the body
    reads from its array ``lane_<name>[j]`` first (unless ``load`` is False) and
    stores back those it assigns (or ``stores``)."""
    used = set(IDENTIFIER.findall(body)) if load else set()
    loads = [f"{name} = lane_{name}[j]" for name in lane if name in used]
    if stores is None:
        stores = [name for name in lane if name in set(ASSIGNED.findall(body))]
    lines = loads + [body] + [f"lane_{name}[j] = {name}" for name in stores]
    return indent(f"for j in range({count}):\n{head}" + indent("\n".join(lines), 1),
                  level)


#: The head of ``bind(BLOCK)``, which every CPU kernel module defines in place of a
#: ``kernel`` (`sweep.kernels.cache.build` calls it with the spec's block): the lanes
#: per block are an argument of the compiled function, so that its text does not depend
#: on them and one compilation serves every block size (but one lane, `scalar_lanes`).
BIND = '''def bind(BLOCK):
    """The kernel for blocks of ``BLOCK`` SIMD lanes."""'''

def block_multiple(block: int, dtype: str = "float64") -> str:
    """The first line of a compiled function over blocks of ``block`` lanes: ``BLOCK``
    (an argument, `BIND`) is a multiple of 8 (`sweep.kernels.spec.check_block`), of 16
    for a float32 kernel whose block is (its vectors hold 16 lanes), and said so, LLVM
    knows each lane loop's trip count is too and drops the checks of a remainder; none
    for one lane.

    Measured side by side on the forced pendulum's rk4 kernel (blocks of 128, 131,072
    starts, AMD EPYC Zen 5, 2 threads, the same bits), against the constant ``BLOCK =
    128`` of the module's text before: float64 921-927 M trajectory-steps/s with a bare
    argument, 943-949 with this line, 933-949 with the constant; float32 1003-1010 with
    a multiple of 8, 1026-1029 with a multiple of 16, 1021-1034 with the constant.
    """
    if block == 1:
        return ""
    shift = 4 if dtype == "float32" and block % 16 == 0 else 3
    return f"    BLOCK = (BLOCK >> {shift}) << {shift}  # a multiple of {1 << shift}\n"


#: The arguments of a fixed-step kernel before ``extra`` (`sweep.kernels.source`'s
#: fixed-step contract; a swing network's and a system's too).
FIXED_ARGUMENTS = ("params", "t0", "dt", "n_steps", "n_transient", "save_every", "out",
                   "status", "saved")
#: The arguments of an adaptive kernel before ``extra`` (`sweep.kernels.source`'s
#: adaptive contract).
ADAPTIVE_ARGUMENTS = ("params", "t0", "t_end", "dt", "t_transient", "rtol", "atol", "out",
                      "status", "stats")


def blocks_head(block: int, extra: str = "", dtype: str = "float64", *,
                arguments: tuple[str, ...] = FIXED_ARGUMENTS, constant_block: bool = False,
                compiled: str = "blocks", trailing: str = "b_first, b_stop",
                wrapper: str | None = None) -> str:
    """The head of a CPU kernel module's body, the one writer of every kernel's head:
    ``bind`` (`BIND`), which makes the Python ``kernel`` (the contract of
    `sweep.kernels.source`) that spreads the compiled function over threads
    (`sweep.kernels.threads.run_blocks`), and the signature and first line of the
    compiled function, whose body follows.

    Parameters
    ----------
    block : int
        Trajectories per block (SIMD lanes): it changes only the compiled function's
        first line (`block_multiple`; the constant with ``constant_block``).
    extra : str
        The kernel's arguments after ``arguments``, as source (``", name, ..."``):
        `sweep.kernels.snippets.kernel_arguments`, a system's attractor catalogue
        (`CATALOGUE_ARGUMENTS`), a swing network's arrays.
    dtype : {"float64", "float32"}
        The kernel's working precision (`block_multiple`).
    arguments : tuple of str
        The kernel's arguments before ``extra``: `FIXED_ARGUMENTS` or
        `ADAPTIVE_ARGUMENTS`.
    constant_block : bool
        The compiled function's first line sets ``BLOCK = block``, a constant of the text
        in place of the argument (the swing network's kernel,
        `sweep.kernels.network`, says why); otherwise ``BLOCK`` stays the argument,
        said to be a multiple of 8 or 16 (`block_multiple`).
    compiled : str
        The compiled function's name.
    trailing : str
        The compiled function's arguments after ``BLOCK``, as source: by default the
        range of blocks it runs (``b_first, b_stop``).
    wrapper : str, optional
        The Python ``kernel``'s body, unindented, which calls ``run_blocks``; by default
        one call over ``ceil(n / BLOCK)`` blocks, ``compiled(arguments, extra, BLOCK,
        b_first, b_stop)`` for each thread's range (a refill kernel's groups:
        `sweep.kernels.refill.groups_head`).

    Returns
    -------
    str
        Module source, from a blank line to the compiled function's first line (none
        for a one-lane block without ``constant_block``).
    """
    signature = ", ".join(arguments) + extra
    if wrapper is None:
        wrapper = f"""run_blocks({compiled}, (params.shape[0] + BLOCK - 1) // BLOCK,
           {", ".join(arguments[:-1])},
           {arguments[-1]}{extra}, BLOCK)"""
    first = (f"    BLOCK = {block}  # a constant (module docstring)\n" if constant_block
             else block_multiple(block, dtype))
    continuation = " " * len(f"def {compiled}(")  # the signature's second line, aligned
    return f'''
{BIND}

    def kernel({signature}):
{indent(wrapper, 2)}
    return kernel


@njit(nogil=True, **JIT)
def {compiled}({signature},
{continuation}BLOCK, {trailing}):
''' + first


#: The kernel arguments of `sweep.kernels.KernelSpec.known_cells`, after ``saved``.
KNOWN_ARGUMENTS = ", known, known_axes"
#: A system kernel's attractor catalogue (observable ``attractor``), after ``saved``
#: (`sweep.kernels.system`; `sweep.system_attractors.catalogue_arguments` makes them).
CATALOGUE_ARGUMENTS = ", cat_points, cat_next, cat_owner"


def indent(code: str, level: int) -> str:
    """``code`` indented by ``level`` levels of four spaces ("" stays "")."""
    return textwrap.indent(code, "    " * level) if code else ""


def allocate(lane: dict[str, str]) -> list[str]:
    """The lines that make each lane variable's array ``lane_<name>`` (name -> dtype)."""
    return [f"lane_{name} = np.empty(BLOCK, dtype=np.{dtype})" for name, dtype in lane.items()]


def skip_unless(flag: str) -> str:
    """A `lane_loop` head that skips the lanes whose boolean ``lane_<flag>`` is False."""
    return f"    if not lane_{flag}[j]:\n        continue\n"


_ALLOCATION = re.compile(r"^\s*lane_(\w+) = np\.empty\(BLOCK, dtype=np\.\w+\)\n", re.MULTILINE)
_LOAD = re.compile(r"^\s*(\w+) = lane_\1\[j\]\n", re.MULTILINE)
_STORE = re.compile(r"^(\s*)lane_(\w+)\[j\] = \2$", re.MULTILINE)
_LANE = re.compile(r"\blane_(\w+)\[j\]")
_LANE_LOOP = re.compile(r"^(\s*)for j in range\((?:BLOCK|n_real)\):$", re.MULTILINE)
_SKIP = re.compile(r"^(\s*)if True:\n\1    if (\w+):\n\1        continue\n", re.MULTILINE)
_BLOCK_START = re.compile(r"^(\s*)base = b \* BLOCK\n", re.MULTILINE)
_LOOP_STATEMENT = re.compile(r"^(\s*)(?:for|while)\b")
_EXIT = re.compile(r"^(\s*)(break|continue)\b")


def _lane_body_exits(kernel: str) -> list[str]:
    """The ``break``/``continue`` statements that belong to a one-lane loop itself
    (not to a loop inside its body), other than the skip head ``if <flag>: continue``."""
    found, stack = [], []  # stack: (indent of a loop statement, is a lane loop)
    lines = kernel.splitlines()
    for k, line in enumerate(lines):
        if not line.strip():
            continue
        depth = len(line) - len(line.lstrip())
        while stack and depth <= stack[-1][0]:
            stack.pop()
        exit_ = _EXIT.match(line)
        if exit_ and stack and stack[-1][1]:
            head = lines[k - 1].strip() if k else ""
            skip = exit_.group(2) == "continue" and head.startswith("if ") and \
                depth == stack[-1][0] + 8
            if not skip:
                found.append(line.strip())
        loop = _LOOP_STATEMENT.match(line)
        if loop:
            stack.append((depth, bool(_LANE_LOOP.match(line))))
    return found


def scalar_lanes(kernel: str, dtypes: dict[str, str]) -> str:
    """A fixed-step kernel of one lane per block (``BLOCK = 1``, the narrow path of a
    handful of trajectories) with its lanes turned into plain variables: allocations
    and the loads from ``lane_<name>[j]`` are dropped, each store becomes the
    conversion the array did (``name = np.<dtype>(name)``, ``dtypes`` as `allocate`
    got them: a float32 kernel keeps observables' state in float64), any other
    ``lane_<name>[j]`` reads ``<name>``, and each one-lane loop ``for j in
    range(...)`` becomes ``if True:`` with ``j = 0`` (a skipped lane's ``continue``
    becomes ``if not <flag>:``).

    The same operations on the same values, so the same bits (``tests/test_blocks.py``,
    ``tests/test_float32.py``); but the state stays in registers from one step to the
    next instead of making a round trip through memory on every step's critical path
    (one trajectory alone is latency-bound). The loops go too because numba's
    ``prange`` lowering (which compiled the kernels until 0.3) mishandled variables that
    live from one inner loop to the next (measured: other bits). Exact for the fixed-step
    kernel, whose every lane loop loads what it reads at its start and stores what it
    changes at its end (`lane_loop`); not for kernels that read a lane array after
    changing the variable without storing it (a rejected adaptive step).

    Raises
    ------
    AssertionError
        If a lane loop's own body leaves it with ``break`` or ``continue`` (other than
        the skip head), which ``if True:`` would turn into an exit from the step loop.
    """
    exits = _lane_body_exits(kernel)
    if exits:
        raise AssertionError(f"a one-lane loop's body has {exits[0]!r}: it cannot become "
                             "plain code")
    kernel = _ALLOCATION.sub("", kernel)
    kernel = _LOAD.sub("", kernel)
    kernel = _STORE.sub(lambda m: f"{m.group(1)}{m.group(2)} = "
                                  f"np.{dtypes[m.group(2)]}({m.group(2)})", kernel)
    kernel = _LANE.sub(r"\1", kernel)
    kernel = _LANE_LOOP.sub(r"\1if True:", kernel)
    kernel = _SKIP.sub(r"\1if not \2:\n", kernel)
    kernel = _BLOCK_START.sub(r"\g<0>\1j = 0\n", kernel)
    if re.search(r"\blane_\w+\[", kernel):
        raise AssertionError("a one-lane kernel kept a lane array")
    return kernel
