#!/usr/bin/env bash
# The package as a user gets it from PyPI, not as the editable install of a checkout
# (which imports the checkout's files, so it hides a file missing from the wheel):
#   1. python -m build: the sdist, then the wheel built FROM the sdist (so the sdist
#      must hold what a build needs);
#   2. both archives hold every tracked file of sweep/ (and the sdist pyproject.toml,
#      README.md and LICENSE), the wheel LICENSE and the `sweep` command;
#   3. the wheel is installed into a fresh virtual environment (python -m venv, no
#      system site-packages; its dependencies at the versions this environment has,
#      from PyPI or pip's cache), and run from a folder outside the checkout:
#      `import sweep` comes from that environment, distribution sweep-pendulum,
#      `sweep --version`, a small `sweep demo` (kernels compiled into an empty cache)
#      and `sweep explore --help`.
# Needs `build` (in the test extra) and network access to PyPI. About 40 s on a 2-core
# machine. Run alone: .ci/wheel_check.sh (PYTHON=... picks the interpreter).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
python="${PYTHON:-python}"
dist_name="sweep-pendulum"      # pyproject.toml's [project] name
started=$SECONDS

work="$(mktemp -d "${TMPDIR:-/tmp}/sweep-wheel-check.XXXXXX")"
trap 'rm -rf "$work"' EXIT
fail() { echo "wheel check: FAILED: $*" >&2; exit 1; }
step() { echo "wheel check: $*"; }

# what the archives must hold: the package's tracked files (every file of sweep/
# outside a git checkout)
# and, in a git checkout, every file it tracks (the sdist may hold no other: no build
# output, test database or cache a working tree gathers)
: >"$work/tracked"
if git -C "$root" rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  # (core.quotepath off: a non-ASCII name as itself, not quoted with octal escapes)
  git -C "$root" -c core.quotepath=off ls-files -- sweep >"$work/expected"
  git -C "$root" -c core.quotepath=off ls-files >"$work/tracked"
else
  (cd "$root" && find sweep -type f ! -path '*/__pycache__/*' ! -name '*.py[co]') >"$work/expected"
fi
[ -s "$work/expected" ] || fail "no files of sweep/ found in $root"

# 1. the sdist, then the wheel from it (isolated builds: hatchling from PyPI)
if ! "$python" -m build --outdir "$work/dist" "$root" >"$work/build.log" 2>&1; then
  tail -n 30 "$work/build.log" >&2
  fail "python -m build did not build the sdist and the wheel (log above)"
fi
sdist=("$work"/dist/*.tar.gz)
wheel=("$work"/dist/*.whl)
[ "${#sdist[@]}" = 1 ] && [ -f "${sdist[0]}" ] || fail "no sdist in $work/dist"
[ "${#wheel[@]}" = 1 ] && [ -f "${wheel[0]}" ] || fail "no wheel in $work/dist"
step "built $(basename "${sdist[0]}") and $(basename "${wheel[0]}") (the wheel from the sdist)"

# 2. the archives' contents
"$python" - "${sdist[0]}" "${wheel[0]}" "$work/expected" "$work/tracked" <<'EOF' \
  || fail "an archive lacks files or holds untracked ones (above)"
import sys, tarfile, zipfile

sdist, wheel, expected, tracked = sys.argv[1:]
package = [line.strip() for line in open(expected) if line.strip()]
tracked = {line.strip() for line in open(tracked) if line.strip()}
with tarfile.open(sdist) as archive:  # sweep_pendulum-X.Y.Z/<path>
    in_sdist = {name.split("/", 1)[1] for name in archive.getnames() if "/" in name}
with zipfile.ZipFile(wheel) as archive:
    in_wheel = set(archive.namelist())
    entry_points = next((archive.read(n).decode() for n in in_wheel
                         if n.endswith(".dist-info/entry_points.txt")), "")
missing = {"sdist": sorted(set(package + ["pyproject.toml", "README.md", "LICENSE"])
                           - in_sdist),
           "wheel": sorted(set(package) - in_wheel)}
if not any(n.endswith(".dist-info/licenses/LICENSE") or n.endswith(".dist-info/LICENSE")
           for n in in_wheel):
    missing["wheel"].append("the LICENSE file in its .dist-info")
if "sweep = sweep.cli:main" not in entry_points:
    missing["wheel"].append("the console script sweep = sweep.cli:main")
# hatchling's sdist takes what the root .gitignore does not exclude, so an output a
# nested .gitignore or a tool's own marker hides from git (docs/_build, .hypothesis)
# would be shipped: the sdist may hold only tracked files and its PKG-INFO
untracked = sorted(in_sdist - tracked - {"PKG-INFO", ""}) if tracked else []
bad = False
if untracked:
    bad = True
    print(f"wheel check: the sdist holds {len(untracked)} files git does not track: "
          f"{', '.join(untracked[:8])}{', ...' if len(untracked) > 8 else ''}",
          file=sys.stderr)
for kind, names in missing.items():
    if names:
        bad = True
        print(f"wheel check: the {kind} lacks {len(names)}: {', '.join(names)}",
              file=sys.stderr)
if bad:
    sys.exit(1)
print(f"wheel check: the sdist and the wheel hold all {len(package)} files of sweep/")
EOF

# 3. a fresh virtual environment, the wheel and its dependencies
"$python" -m venv "$work/venv" || fail "python -m venv failed"
venv="$work/venv/bin"
# the dependencies at this environment's versions (pip's cache has them; the same
# versions as the test suite's), never a constraint on the package itself
"$python" -m pip freeze --exclude-editable 2>/dev/null \
  | grep -E '^[A-Za-z0-9][A-Za-z0-9._-]*==' | grep -viE "^(sweep|sweep-pendulum|sweep_pendulum)==" \
  >"$work/constraints.txt" || true
if ! "$venv/python" -m pip install --disable-pip-version-check -q -c "$work/constraints.txt" \
     "${wheel[0]}" >"$work/install.log" 2>&1; then
  grep -v "is ignored: it is neither a file nor a directory" "$work/install.log" | tail -n 30 >&2
  fail "pip could not install the wheel into a fresh virtual environment (log above)"
fi
step "installed the wheel into a fresh virtual environment"

# from a folder outside the checkout, with nothing of the checkout on the path
mkdir "$work/outside"
cd "$work/outside"
run() { env -u PYTHONPATH -u PYTHONHOME -u PYTHONSTARTUP -u PYTHONUSERBASE \
          SWEEP_CACHE_DIR="$work/kernels" MPLBACKEND=Agg "$@"; }
run "$venv/python" - "$work/venv" "$dist_name" "$root" <<'EOF' || fail "import sweep from the wheel (above)"
import importlib.metadata as metadata, pathlib, sys

import sweep

venv, dist_name, checkout = map(pathlib.Path, sys.argv[1:])
where = pathlib.Path(sweep.__file__).resolve()
assert where.is_relative_to(venv.resolve()), f"sweep imported from {where}, not the venv"
assert not where.is_relative_to(checkout.resolve()), f"sweep imported from the checkout"
providers = metadata.packages_distributions().get("sweep")
assert providers == [str(dist_name)], f"import sweep is provided by {providers}"
version = metadata.version(str(dist_name))
assert version == sweep.__version__, (version, sweep.__version__)
print(f"wheel check: import sweep {version} from the venv, distribution {dist_name}")
EOF
version="$(run "$venv/sweep" --version)" || fail "sweep --version"
[ "$version" = "sweep $(run "$venv/python" -c 'import sweep; print(sweep.__version__)')" ] \
  || fail "sweep --version printed '$version'"
run "$venv/sweep" demo --size 21 -o demo --no-progress >"$work/demo.log" 2>&1 \
  || { cat "$work/demo.log" >&2; fail "sweep demo --size 21"; }
[ -s demo/demo.nc ] || fail "sweep demo wrote no demo/demo.nc"
pngs=(demo/*.png)
[ "${#pngs[@]}" -ge 2 ] && [ -s "${pngs[0]}" ] || fail "sweep demo wrote fewer than 2 PNG maps"
step "sweep demo --size 21: $(head -n 1 "$work/demo.log")"
run "$venv/sweep" explore --help >"$work/explore.txt" 2>&1 \
  || { cat "$work/explore.txt" >&2; fail "sweep explore --help"; }
grep -q "^usage: sweep explore" "$work/explore.txt" || fail "sweep explore --help printed no usage"
step "sweep explore --help: ok"
step "passed in $((SECONDS - started)) s"
