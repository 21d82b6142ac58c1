"""Compiled kernels for the per-frame hot loops, where Numba (the ``fast`` extra) is installed.

The simulations that stay on the CPU (windshield drops, spray launches, the ripples' CPU solver) are vectorised
NumPy: each step is hundreds of small array calls, and at a few thousand elements the ~1–2 µs each call costs
in Python and NumPy's dispatch is most of the time. A loop compiled by Numba does the same arithmetic in one
call. Every kernel has a NumPy twin that stays the fallback where Numba is missing and the oracle its tests
compare against; ``active()`` says which one runs.

``RAINROAD_JIT=0`` turns the kernels off for a process (A/B benchmarks, bisecting a difference); ``forced`` does
it for a block (tests). Kernels compile on their first call (about a second each) and are cached on disk beside
their module, so later processes load them (each on its first call, or all at once: ``preload``). Numba keys a
cached kernel to its own file's contents alone, but a kernel carries its callees' code and the values of the
constants it imports: ``kernel`` adds those files' hashes to its key, so an edit of a callee's file alone (a ``git
pull``), or of a module whose constants a kernel imports, recompiles it instead of running stale code.
"""

from __future__ import annotations

import ast
import hashlib
import importlib.util
import os
import subprocess
import sys
import sysconfig
import types
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TypeVar

try:
    import numba
except ImportError:  # the fast extra is optional: every kernel has a NumPy twin
    numba = None

F = TypeVar("F", bound=Callable)
T = TypeVar("T")

ENV_VAR = "RAINROAD_JIT"
AVAILABLE: bool = numba is not None
_KERNELS: list = []  # every compiled dispatcher made so far (``cold`` looks at their disk caches)
# A source file with kernels → the other files their compiled code takes code from (the kernels they call, and the
# files those take code from): a kernel of another module that refers to this one by name depends on them too.
_DEPENDS: dict[str, frozenset[str]] = {}
_PACKAGE = os.path.realpath(os.path.dirname(__file__)) + os.sep  # this package's files
# Installed libraries' and the standard library's files are not followed (numpy's constants, math's functions).
_LIBRARIES = tuple({os.path.realpath(sysconfig.get_paths()[key]) + os.sep for key in ("stdlib", "purelib", "platlib")})


def _from_environment() -> bool:
    raw = os.environ.get(ENV_VAR, "1").strip().lower()
    if raw in ("1", "on", "true", "yes", ""):
        return AVAILABLE
    if raw in ("0", "off", "false", "no"):
        return False
    raise ValueError(f"{ENV_VAR}={os.environ[ENV_VAR]!r}: expected 1/on or 0/off")


_active: bool = _from_environment()


def active() -> bool:
    """Whether the compiled kernels run (Numba installed and not turned off); otherwise their NumPy twins."""
    return _active


def set_active(on: bool) -> None:
    """Turn the compiled kernels on or off for this process. Turning them on without Numba is an error."""
    global _active
    if on and not AVAILABLE:
        raise RuntimeError("compiled kernels need Numba: pip install 'rainroad[fast]'")
    _active = bool(on)


@contextmanager
def forced(on: bool) -> Iterator[None]:
    """Run a block with the kernels on or off (tests of a kernel against its NumPy twin)."""
    before = _active
    set_active(on)
    try:
        yield
    finally:
        set_active(before)


def twin_and_kernel(run: Callable[[], T]) -> tuple[T, T]:
    """(``run()`` with the NumPy twins, ``run()`` with the kernels): what a twin test compares."""
    with forced(False):
        twin = run()
    with forced(True):
        kernel = run()
    return twin, kernel


def kernel(fn: F) -> F:
    """``fn`` compiled by Numba in nopython mode (no GIL, cached on disk), or ``fn`` itself without Numba.

    Callers run a kernel only while ``active()``; tests may also call the plain function (``fn`` without Numba,
    ``kernel.py_func`` with it) on small inputs, so a kernel's logic is checked even where Numba is missing."""
    if numba is None:
        return fn
    dispatcher = numba.njit(cache=True, nogil=True)(fn)
    _KERNELS.append(dispatcher)
    _stamp_dependencies(dispatcher, fn)
    return dispatcher


def _code_names(code) -> set[str]:
    """The global names ``code`` and the code objects nested in it refer to."""
    names = set(code.co_names)
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            names |= _code_names(const)
    return names


def _followed(path: str) -> bool:
    """Whether a source file's code may be compiled into a kernel: this package's, and any outside the installed
    libraries (a user's own kernels)."""
    return path.startswith(_PACKAGE) or not path.startswith(_LIBRARIES)


_IMPORTED: dict[str, dict[str, str]] = {}  # source file → {name bound by ``from m import name``: m}


def _imported_names(path: str, package: str | None) -> dict[str, str]:
    """The names the module at ``path`` binds with ``from m import name`` (relative ones resolved), by name."""
    names = _IMPORTED.get(path)
    if names is None:
        names = {}
        for node in ast.walk(ast.parse(Path(path).read_bytes())):
            if isinstance(node, ast.ImportFrom) and node.module != "__future__":
                try:
                    module = importlib.util.resolve_name("." * node.level + (node.module or ""), package)
                except (ImportError, ValueError):
                    continue
                names.update({alias.asname or alias.name: module for alias in node.names})
        _IMPORTED[path] = names
    return names


def _constant_sources(name: str, module_name: str | None, own: str) -> set[str]:
    """The files a constant ``name`` imported from ``module_name`` passes through, to the one that binds it (a
    re-export chain: a package's __init__ passing a name on)."""
    files = set()
    for _ in range(8):
        module = sys.modules.get(module_name or "")
        path = getattr(module, "__file__", None)
        if path is None:
            break
        path = os.path.realpath(path)
        if path != own and _followed(path):
            files.add(path)
        module_name = _imported_names(path, module.__package__).get(name)
    return files


def dependency_files(fn) -> frozenset[str]:
    """The source files other than its own whose code or constants ``fn``'s compiled code takes in (Numba freezes
    a global's value into the code): the kernels it calls (``g(…)``), the functions (an ``overload``ed helper),
    modules (``m.g(…)``, ``m.CONSTANT``) and constants (``from m import CONSTANT``) it names, with the files those
    files' kernels take in. Installed libraries are not followed. Defined above ``fn`` (imported, or earlier in its
    file), they are known when ``fn`` is decorated."""
    own = os.path.realpath(fn.__code__.co_filename)
    imported = None
    files: set[str] = set()
    for name in _code_names(fn.__code__):
        if name not in fn.__globals__:
            continue
        value = fn.__globals__[name]
        py_func = getattr(value, "py_func", None)  # a Numba dispatcher
        if isinstance(py_func, types.FunctionType):
            path = py_func.__code__.co_filename
        elif isinstance(value, types.FunctionType):
            path = value.__code__.co_filename
        elif isinstance(value, types.ModuleType):
            path = getattr(value, "__file__", None)
        else:  # a constant
            if imported is None:
                imported = _imported_names(own, fn.__globals__.get("__package__"))
            files |= _constant_sources(name, imported.get(name), own)
            continue
        if path is None:
            continue
        path = os.path.realpath(path)
        if path != own and _followed(path):
            files.add(path)
            files |= _DEPENDS.get(path, frozenset())
    files.discard(own)
    _DEPENDS[own] = _DEPENDS.get(own, frozenset()) | files
    return frozenset(files)


_SOURCE_HASHES: dict[str, bytes] = {}  # path → SHA-256 of its bytes, read once per process


def _source_hash(path: str) -> bytes:
    digest = _SOURCE_HASHES.get(path)
    if digest is None:
        digest = _SOURCE_HASHES[path] = hashlib.sha256(Path(path).read_bytes()).digest()
    return digest


def _stamp_dependencies(dispatcher, fn) -> None:
    """Key ``dispatcher``'s disk cache by the contents of ``dependency_files(fn)`` too, as Numba keys it by its own
    file's (a SHA-256; its cache index takes any picklable stamp). A kernel that calls nothing from another file
    keeps Numba's own stamp."""
    files = dependency_files(fn)
    if not files:
        return
    try:
        cache_file = dispatcher._cache._cache_file
        cache_file._source_stamp = (cache_file._source_stamp, tuple((p, _source_hash(p)) for p in sorted(files)))
    except Exception:  # noqa: BLE001 - a Numba without these internals (or a file gone): its own stamp, as before
        return


def preload() -> int:
    """Load into this process every compilation of the kernels defined so far that Numba's disk cache holds for
    this machine and these sources. A kernel otherwise loads on its first call with new argument types, ~5–25 ms
    each (~0.3 s for the ~40 of a first frame), and a path first taken mid-drive (the glass full, the first wipe, a
    lane change) stalls that frame. Returns the compilations loaded: 0 while the kernels are off, without Numba, or
    when everything cached is loaded already."""
    if not _active:
        return 0
    loaded = 0
    for dispatcher in _KERNELS:
        for signature in _cached_signatures(dispatcher):
            if signature in dispatcher.overloads:
                continue
            try:
                dispatcher.compile(signature)  # found in the cache under the same key: a load, not a compile
            except Exception:  # noqa: BLE001 - a speed-up only: such a kernel compiles on its first call, as before
                continue
            loaded += 1
    return loaded


def _cached_signatures(dispatcher) -> list[tuple]:
    """The argument types of ``dispatcher``'s current disk-cache entries: those under this machine's code
    generator and this function's bytecode (Numba's index key; an entry left by another CPU or an older source
    would compile instead of load). Numba's cache internals; any surprise reads as none."""
    try:
        cache = dispatcher._cache
        codegen = dispatcher.targetctx.codegen()
        return [tuple(key[0]) for key in cache._cache_file._load_index() if key == cache._index_key(key[0], codegen)]
    except Exception:  # noqa: BLE001 - a Numba without these internals: the kernels load on their first calls
        return []


def describe() -> str:
    """One line for benchmark headers and the Rain Manager: which path runs and why."""
    if _active:
        return f"compiled kernels (Numba {numba.__version__})"
    if not AVAILABLE:
        return "NumPy (Numba not installed)"
    if _warming is not None:
        return "NumPy while the kernels compile (first start; a minute at most)"
    return f"NumPy ({ENV_VAR}=0 or turned off)"


# --- a cold start without a frozen window --------------------------------------------------------------------
# Compiling every kernel takes ~40 s on a small machine; lazily, the window's first frame would hang that long.
# The window instead runs the NumPy twins while a child process (``python -m rain_core.warmup``) compiles the
# kernels into Numba's disk cache, and turns them on when it is done: their first calls then load from the cache.

_warming: WarmUp | None = None


def _loads_from_disk(dispatcher) -> bool:
    """Whether Numba's disk cache holds a current compilation of ``dispatcher`` (Numba's FunctionCache internals;
    any surprise reads as "no", which costs at most one needless warm-up)."""
    try:
        return bool(dispatcher._cache._cache_file._load_index())
    except Exception:  # noqa: BLE001 - a Numba without these internals: assume cold
        return False


def _stamp_path() -> Path | None:
    """A file saying a warm-up finished for these kernel sources (and the files they take code and constants from:
    an edit there recompiles them too), this Numba and this Python: a kernel the warm-up scene never calls would
    otherwise make every start look cold."""
    if not _KERNELS:
        return None
    digest = hashlib.sha1(f"{numba.__version__} {sys.version}".encode())
    files = {os.path.realpath(d.py_func.__code__.co_filename) for d in _KERNELS}
    for name in sorted(files.union(*_DEPENDS.values())):
        digest.update(_source_hash(name))
    try:
        folder = sorted(d._cache._cache_path for d in _KERNELS)[0]
    except Exception:  # noqa: BLE001 - no cache folder known: no stamp
        return None
    return Path(folder) / f"rainroad-kernels-{digest.hexdigest()[:16]}.warm"


def cold() -> bool:
    """Whether the kernels defined so far would compile on their first call (nothing current on disk and no
    warm-up has finished for these sources)."""
    return cold_count() > 0


def cold_count() -> int:
    """How many of the kernels defined so far have no current compilation on disk (0 once a warm-up finished for
    these sources): each compiles on its first call, up to about a second."""
    if not AVAILABLE or not _KERNELS:
        return 0
    stamp = _stamp_path()
    if stamp is not None and stamp.exists():
        return 0
    return sum(not _loads_from_disk(d) for d in _KERNELS)


def mark_warm() -> None:
    """Record that the kernels of these sources are compiled on disk (the warm-up's last step)."""
    stamp = _stamp_path()
    if stamp is not None:
        stamp.write_text("compiled by python -m rain_core.warmup\n")


class WarmUp:
    """The kernels compiling in a child process while this one runs their NumPy twins; ``poll`` each frame."""

    def __init__(self, process: subprocess.Popen):
        self.process = process

    @classmethod
    def start(cls) -> WarmUp | None:
        """Start a warm-up when the kernels are on and cold (call after the effects are imported); None when there
        is nothing to do. The kernels stay off until ``poll`` sees the child finish."""
        global _warming
        if not _active or not cold():
            return None
        process = subprocess.Popen([sys.executable, "-m", "rain_core.warmup"], stdout=subprocess.DEVNULL,
                                   stderr=subprocess.DEVNULL, stdin=subprocess.DEVNULL)
        _warming = cls(process)
        set_active(False)
        return _warming

    def poll(self) -> bool:
        """True once the child has ended; the kernels are then on (also when it failed: they compile lazily)."""
        global _warming
        if self.process.poll() is None:
            return False
        if _warming is self:
            _warming = None
            set_active(True)
            preload()  # one pause now (the first frame with the kernels would load most of them anyway)
        return True
