"""What the benchmarks say about the machine they ran on: one line for a report
(`machine`), the CPU's feature flags (`cpu_flags`), run_all.py's details (CPU,
SIMD, gcc and what -march=native means to it, numba, LLVM's CPU name:
`machine_details`) and both with the date (`stamp`); where a script's results go
(`write_results`)."""

from __future__ import annotations

import json
import os
import platform
import re
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numba

#: The C reference's source (`native_vector_registers` compiles it to assembly)
C_SOURCE = Path(__file__).resolve().parent / "c_reference" / "pendulum.c"


def machine() -> str:
    """A one-line description of this machine."""
    cpu = platform.processor() or "unknown CPU"
    try:
        with open("/proc/cpuinfo") as handle:
            for line in handle:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, numba {numba.__version__}, " \
           f"{numba.get_num_threads()} threads"


def cpu_flags() -> set[str]:
    """The CPU's feature flags from /proc/cpuinfo (empty where unreadable)."""
    try:
        with open("/proc/cpuinfo") as handle:
            for line in handle:
                if line.startswith("flags"):
                    return set(line.split(":", 1)[1].split())
    except OSError:
        pass
    return set()


def native_vector_registers() -> str | None:
    """Which vector registers gcc's -march=native code uses for the polynomial-sine
    kernel here ('zmm (512-bit)', 'ymm (256-bit)', ...), from its assembly."""
    gcc = shutil.which("gcc")
    if gcc is None:
        return None
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "p.s"
        proc = subprocess.run([gcc, "-O3", "-march=native", "-fopenmp", "-S",
                               "-DSIN_VARIANT=4", str(C_SOURCE), "-o", str(out)],
                              capture_output=True, text=True, check=False)
        if proc.returncode != 0:
            return None
        asm = out.read_text()
    for reg, bits in (("zmm", 512), ("ymm", 256), ("xmm", 128)):
        if re.search(rf"%{reg}\d", asm):
            return f"{reg} ({bits}-bit)"
    return "none"


def gcc_info() -> dict:
    """gcc's version and what -march=native means to it (None without gcc)."""
    gcc = shutil.which("gcc")
    if gcc is None:
        return {"compiler": None}
    version = subprocess.run([gcc, "--version"], capture_output=True, text=True,
                             check=False).stdout.splitlines()[0]
    target = subprocess.run([gcc, "-march=native", "-Q", "--help=target"],
                            capture_output=True, text=True, check=False).stdout
    march = re.search(r"^\s+-march=\s+(\S+)", target, re.M)
    return {"compiler": version, "march_native": march.group(1) if march else None,
            "march_native_vector_registers": native_vector_registers()}


def machine_details() -> dict:
    """CPU model (lscpu), cores, SIMD flags, compiler, numba: the report's machine."""
    info = {"cpu_model": None, "cores": os.cpu_count()}
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, check=False).stdout
        for line in out.splitlines():
            key, _, value = line.partition(":")
            key, value = key.strip(), value.strip()
            if key in ("Model name", "Vendor ID", "CPU family", "Model",
                       "Thread(s) per core", "Core(s) per socket", "Hypervisor vendor"):
                info[key] = value
        info["cpu_model"] = info.pop("Model name", None)
    except OSError:
        pass
    flags = cpu_flags()
    info["simd"] = " ".join(f for f in ("avx2", "fma", "avx512f", "avx512dq", "avx512vl")
                            if f in flags)
    info["avx512f"] = "avx512f" in flags
    import llvmlite
    import llvmlite.binding

    info.update(gcc_info(), numba=numba.__version__, llvmlite=llvmlite.__version__,
                numba_threads=numba.get_num_threads(),
                llvm_cpu=llvmlite.binding.get_host_cpu_name())  # what LLVM tunes for
    return info


def machine_lines(r) -> list[str]:
    """Markdown bullet lines on the machine of a results dict (its ``machine_details``,
    or ``details`` as `stamp` writes it): CPU, compiler, numba."""
    d = r.get("machine_details") or r.get("details")
    if not d:
        return []
    return [f"- CPU: {d.get('cpu_model')} ({d.get('Vendor ID', '?')}, family "
            f"{d.get('CPU family', '?')} model {d.get('Model', '?')}), {d['cores']} cores; "
            f"SIMD: {d['simd']}; hypervisor: {d.get('Hypervisor vendor', 'none')}",
            f"- compiler: {d.get('compiler')}; `-march=native` means "
            f"`{d.get('march_native')}` to it, and its code for the polynomial-sine kernel "
            f"uses {d.get('march_native_vector_registers')} vector registers",
            f"- numba {d['numba']} (llvmlite {d['llvmlite']}), {d['numba_threads']} threads"]


def stamp() -> dict:
    """When and where a benchmark ran: ``date`` (local time), ``machine`` (one line)
    and ``details`` (`machine_details`), to open a results dict with."""
    return {"date": time.strftime("%Y-%m-%d %H:%M"), "machine": machine(),
            "details": machine_details()}


def write_results(out: Path, result: dict, text: str) -> None:
    """Write a benchmark's ``result`` to ``<out>.json`` and its report ``text`` to
    ``<out>.md`` (making the folder), and print the report."""
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps(result, indent=1, default=str))
    out.with_suffix(".md").write_text(text)
    print(text)
