"""Find (or make) the Python modules lcm-gen generates for rtfuse's types.

Generated code is never committed, so a tool needs the modules from a build
tree, an installed package, or, as a last resort, generates them itself into
a per-user cache so that the tools also work from a bare checkout.
"""

import hashlib
import importlib
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import List, Optional

ENV_VAR = "RTFUSE_LCMTYPES_PYTHON"
PACKAGE = "rtfuse"
REPO_ROOT = Path(__file__).resolve().parents[2]
INSTALLED_DIR = Path("/usr/share/rtfuse/python")


class LcmTypesError(RuntimeError):
    pass


def _has_package(d: Path) -> bool:
    return (d / PACKAGE / "__init__.py").is_file()


def candidate_dirs(repo_root: Path = REPO_ROOT) -> List[Path]:
    return [
        repo_root / "build" / "release" / "lcmtypes" / "python",
        repo_root / "build" / "test" / "lcmtypes" / "python",
        INSTALLED_DIR,
    ]


def _cache_root() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(
        os.path.expanduser("~"), ".cache")
    return Path(base) / "rtfuse" / "lcmtypes-python"


def generate(lcm_dir: Path, cache_root: Optional[Path] = None) -> Path:
    """Generate the modules from lcm_dir/*.lcm into a cache dir and return it.

    The cache is keyed by the .lcm contents so an edited type is never served
    from a stale copy.
    """
    files = sorted(lcm_dir.glob("*.lcm"))
    if not files:
        raise LcmTypesError(f"no .lcm files in {lcm_dir}")
    lcm_gen = shutil.which("lcm-gen")
    if lcm_gen is None:
        raise LcmTypesError(
            "lcm-gen not found, needed to generate the rtfuse Python types "
            "(apt-get install liblcm-bin), or set "
            f"{ENV_VAR} to a directory holding the generated '{PACKAGE}' package")
    h = hashlib.sha256()
    for f in files:
        h.update(f.name.encode())
        h.update(b"\0")
        h.update(f.read_bytes())
    root = cache_root or _cache_root()
    target = root / h.hexdigest()[:16]
    if _has_package(target):
        return target
    root.mkdir(parents=True, exist_ok=True)
    # Generate beside the target and rename, so concurrent tools (parallel
    # ctest) never import a half-written package.
    tmp = Path(tempfile.mkdtemp(prefix=".gen-", dir=root))
    try:
        proc = subprocess.run([lcm_gen, "-p", "--ppath", str(tmp)] +
                              [str(f) for f in files],
                              capture_output=True, text=True)
        if proc.returncode != 0:
            raise LcmTypesError(
                f"lcm-gen failed ({proc.returncode}): {proc.stderr.strip()}")
        if not _has_package(tmp):
            raise LcmTypesError(f"lcm-gen produced no '{PACKAGE}' package in {tmp}")
        try:
            os.rename(tmp, target)
        except OSError:
            if not _has_package(target):  # lost a race only if the winner is done
                raise
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    return target


def find_lcmtypes_python(repo_root: Path = REPO_ROOT) -> Path:
    """Directory to put on sys.path so that `import rtfuse` gives our types."""
    env = os.environ.get(ENV_VAR)
    if env:
        # An explicit setting that is wrong is an error, not a hint to look
        # elsewhere: silently using other (maybe stale) types hides mistakes.
        d = Path(env)
        if not _has_package(d):
            raise LcmTypesError(
                f"{ENV_VAR}={env} does not contain the generated "
                f"'{PACKAGE}' package ({d / PACKAGE / '__init__.py'} missing)")
        return d
    for d in candidate_dirs(repo_root):
        if _has_package(d):
            return d
    lcm_dir = repo_root / "lcmtypes"
    if not lcm_dir.is_dir():
        raise LcmTypesError(
            "rtfuse Python lcmtypes not found: set "
            f"{ENV_VAR}, build the project, or install rtfuse "
            f"(looked in {', '.join(str(d) for d in candidate_dirs(repo_root))})")
    return generate(lcm_dir)


def import_lcmtypes(repo_root: Path = REPO_ROOT):
    """Import and return the generated `rtfuse` package."""
    d = str(find_lcmtypes_python(repo_root))
    if d not in sys.path:
        sys.path.insert(0, d)
    mod = importlib.import_module(PACKAGE)
    where = Path(mod.__file__).resolve().parent.parent
    if where != Path(d).resolve():
        raise LcmTypesError(
            f"'{PACKAGE}' was already imported from {where}, not {d}")
    return mod
