"""The compiled kernels: the one place that imports numba, and the library-wide switch.

Hot inner loops (the backward pass, with or without box QPs, the FDDP expected improvement, the rollout's
control update, the cost stack's activations and Gauss-Newton sums, Euler's step and chain rule) exist twice:
as a numba-compiled kernel and as a numpy twin that gives the same numbers to round-off (tested to 1e-12).
Each kernel lives beside its twin:

=====================================  ==========================================================
``solvers/riccati_kernel.py``          ``riccati_pass`` (twin: ``SolverDDP.computeActionValueFunction``,
                                       ``computeGains``, ``computeValueFunction`` over the horizon);
                                       ``expected_terms`` (twin: ``SolverFDDP.updateExpectedImprovement``);
                                       ``feedback_control`` / ``feedback_control_numpy``
``solvers/box_kernel.py``              ``box_pass`` (twin: ``BoxSolverMixin.computeGains`` with
                                       :class:`~crocopy.solvers.box_qp.BoxQP`)
``solvers/intro_riccati_kernel.py``    ``intro_pass`` (twin: ``SolverIntro``'s constrained node steps over
                                       the horizon); ``row_norm`` (twin: ``SolverIntro._norm`` of every ``h``)
``costs/stack_kernel.py``              ``activation_values``, ``activation_derivatives``,
                                       ``accumulate`` and their ``*_numpy`` twins; ``stack_values``,
                                       ``stack_derivatives_and_sums`` (compiled nodes only; twin: the
                                       activations' own ``calc``/``calcDiff``)
``integrators/euler_kernel.py``        ``euler_step``, ``euler_chain``, ``add_integrate_jacobian``
                                       and their ``*_numpy`` twins
``models/rbd/euler_node_kernel.py``    a whole Euler node of free forward dynamics (twin: the node's
                                       Python path; see :mod:`crocopy.solvers.compiled_nodes`)
=====================================  ==========================================================

One setting chooses between them for the whole library (default: on when numba is installed)::

    crocopy.set_kernels(False)          # numpy twins from now on
    crocopy.kernels_enabled()           # -> False
    with crocopy.use_kernels(True):     # compiled kernels inside the block, then back
        solver.solve()

The consumers read the switch at every call, so it may be flipped between (not during) solves.
It is process-wide and not thread-local; a worker process that is spawned rather than forked (e.g.
by :func:`crocopy.solve_many` under the ``spawn``/``forkserver`` start methods) starts from the
default.  Without numba, :data:`available` is False, the kernel functions stay plain Python (never
called by the library) and ``set_kernels(True)`` raises.

Kernels are compiled with ``numba.njit(cache=True)``: the machine code is cached on disk and
loaded, not recompiled, by later processes.  The cache is numba's: ``NUMBA_CACHE_DIR`` when set,
else beside the sources (``__pycache__``); when crocopy's folder is read-only (a system install) and
``NUMBA_CACHE_DIR`` is unset, it is crocopy's user cache folder
(:func:`crocopy.user_cache.user_cache_dir` ``/ "numba"``).  :func:`cache_is_cold` tells, without
compiling anything, whether some kernel has nothing usable in that cache (a fresh install, a new
numba, an edited kernel); ``crocopy compile`` fills it ahead of the first solve.  A cache file that
cannot be read back (truncated by a full disk or a killed write, garbage, another function's entry)
is deleted with a one-line warning on the ``"crocopy"`` logger and the kernel is compiled again, so
the run goes on.

An installed copy may also hold kernels compiled when its wheel was built (``pip install .``, see
``build_support/crocopy_build.py``): numba's index and data files in :data:`SHIPPED_DIR` (a folder per
package), read before the cache above and never written at run time.  An entry there is used only when
everything numba keys an entry by matches: the numba version, the kernel's source file (its SHA-256,
:func:`source_digest`) and bytecode, the argument types, and the CPU (name and features) the process
compiles for; anything else (another machine, an edited kernel, another numba) finds no entry there and
compiles as without it.  ``CROCOPY_SHIPPED_KERNELS=0`` (:data:`SHIPPED_SWITCH`) ignores that folder.

A subclass that overrides a step a kernel fuses (a solver's ``computeGains``, a multibody state's
``integrate``, an activation's ``calc``) keeps its override: that step then runs in Python/numpy.
This is logged once per class and step at DEBUG level on the ``"crocopy"`` logger
(``logging.getLogger("crocopy").setLevel(logging.DEBUG)`` to see it).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import inspect
import logging
import os
from collections.abc import Callable, Iterable, Iterator

import numpy as np

from .user_cache import user_cache_dir

try:
    import numba
    import numba.extending
except ImportError:  # pragma: no cover - exercised only without numba (tested in a subprocess)
    numba = None

available: bool = numba is not None
"""True when numba could be imported."""

active: bool = available
"""True while the library runs its compiled kernels.  The hot paths read this flag; change it only
through :func:`set_kernels` / :func:`use_kernels`."""

_logged: set[tuple[type, str]] = set()
logger = logging.getLogger("crocopy")

KERNELS: list = []
"""Every kernel made by :func:`compiled` (numba dispatchers), in the order the modules defined them."""
_KERNEL_IDS: set[int] = set()


def cache_dir_fallback(package_dir: str, numba_cache_dir: str) -> str:
    """The folder numba should cache crocopy's kernels in: ``numba_cache_dir`` (``NUMBA_CACHE_DIR``) when
    set, else ``""`` (numba's default, beside the sources) when ``package_dir`` is writable, else
    :func:`~crocopy.user_cache.user_cache_dir` ``/ "numba"``."""
    if numba_cache_dir or os.access(package_dir, os.W_OK):
        return numba_cache_dir
    return str(user_cache_dir("numba"))


cache_dir: str = cache_dir_fallback(os.path.dirname(__file__), numba.config.CACHE_DIR) if available else ""
"""Where :func:`compiled` caches the kernels (``""``: beside the sources), see :func:`cache_dir_fallback`."""


SHIPPED_DIR: str = os.path.join(os.path.dirname(os.path.abspath(__file__)), "_kernel_cache")
"""Where a wheel ships the kernels compiled when it was built (absent in a checkout or an editable install)."""

BUILD_SWITCH = "CROCOPY_BUILD_KERNEL_CACHE"
"""Set to ``"1"`` (by the wheel build only) to write every kernel compiled into :data:`SHIPPED_DIR`."""

SHIPPED_SWITCH = "CROCOPY_SHIPPED_KERNELS"
"""Set to ``"0"`` to ignore :data:`SHIPPED_DIR` (every kernel then comes from numba's cache or compiles)."""


@functools.cache
def _digest(path: str, size: int, mtime_ns: int) -> str:
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def source_digest(function: Callable) -> str:
    """SHA-256 of the source file defining ``function`` (what the entries of :data:`SHIPPED_DIR` are stamped
    with, whatever numba's own stamp); ``""`` when there is no such file."""
    path = function.__code__.co_filename
    try:
        stat = os.stat(path)
    except OSError:
        return ""
    return _digest(path, stat.st_size, stat.st_mtime_ns)


def _identity(path: str) -> tuple[int, int, int]:
    """What tells one version of the file at ``path`` from another (OSError if there is none)."""
    stat = os.stat(path)
    return stat.st_ino, stat.st_size, stat.st_mtime_ns


def set_aside(path: str, seen: tuple[int, int, int], reason: BaseException) -> None:
    """Delete the damaged cache file ``path`` if it is still the version ``seen`` (:func:`_identity`; a process
    may have written a good one meanwhile) and log it in one line at WARNING level on the ``crocopy`` logger."""
    with contextlib.suppress(OSError):
        if _identity(path) == seen:
            os.unlink(path)
    detail = " ".join(str(reason).split())[:80]
    logger.warning("crocopy: damaged kernel cache file %s set aside (%s%s), compiling it again",
                   path, type(reason).__name__, f": {detail}" if detail else "")


if available:
    from numba.core import caching as _caching
    from numba.core import sigutils as _sigutils
    from numba.core.utils import _dynamic_modname

    class _GuardedCacheFile(_caching.IndexDataCacheFile):
        """numba's index and data files of one kernel, where a file that cannot be read back (truncated by a
        full disk or a killed write, garbage, another program's) is set aside (:func:`set_aside`) and read as
        missing, so that the kernel is compiled and saved again."""

        last_data: tuple[str, tuple[int, int, int]] | None = None
        """The data file read last and its :func:`_identity`, for :meth:`_GuardedCache._load_overload`."""

        def _load_index(self) -> dict:
            try:
                seen = _identity(self._index_path)
            except OSError:  # no index (yet), or none that can be read: the kernels compile
                return {}
            try:
                overloads = super()._load_index()
                if not isinstance(overloads, dict) or not all(isinstance(v, str) for v in overloads.values()):
                    raise TypeError(f"an index holding a {type(overloads).__name__}, not file names")
            except FileNotFoundError:
                return {}
            except Exception as exc:  # noqa: BLE001 - whatever unpickling an unreadable file raises
                set_aside(self._index_path, seen, exc)
                return {}
            return overloads

        def _load_data(self, name: str) -> object:
            path = self._data_path(name)
            seen = _identity(path)  # OSError: numba reads the entry as missing
            try:
                data = super()._load_data(name)
            except OSError:
                raise
            except Exception as exc:  # noqa: BLE001 - whatever unpickling an unreadable file raises
                set_aside(path, seen, exc)
                return None
            self.last_data = path, seen
            return data

    class _GuardedCache(_caching.FunctionCache):
        """numba's cache of one kernel (``numba.njit(cache=True)``) reading through :class:`_GuardedCacheFile`,
        and refusing (setting aside) an entry that rebuilds another function or signature, or does not rebuild."""

        def __init__(self, py_func: Callable) -> None:
            super().__init__(py_func)
            self._cache_file = _GuardedCacheFile(self._cache_path, self._impl.filename_base,
                                                 self._impl.locator.get_source_stamp())
            self.readers = [self._cache_file]
            """The cache files an entry is looked up in, in order: the shipped ones, then numba's."""
            building = os.environ.get(BUILD_SWITCH) == "1"
            if building or (os.environ.get(SHIPPED_SWITCH) != "0" and os.path.isdir(SHIPPED_DIR)):
                # one folder per package: numba's file names omit the package
                folder = os.path.join(SHIPPED_DIR, *(py_func.__module__ or "").split(".")[:-1])
                if building:
                    os.makedirs(folder, exist_ok=True)
                shipped = _GuardedCacheFile(folder, self._impl.filename_base, source_digest(py_func))
                self.readers.insert(0, shipped)
                if building:
                    self.readers, self._cache_file = [shipped], shipped

        wrapperless = False
        """True while the dispatcher loads or saves an entry compiled without the Python wrapper."""

        def _index_key(self, sig, codegen):
            key = super()._index_key(sig, codegen)
            return (*key, "for kernels") if self.wrapperless else key

        def _load_overload(self, sig, target_context):
            if not self._enabled:
                return None
            key = self._index_key(sig, target_context.codegen())
            for reader in self.readers:
                data = reader.load(key)
                if data is None:
                    continue
                try:
                    fndesc, signature = data[1], data[3]
                    args = tuple(_sigutils.normalize_signature(sig)[0])
                    expected = self._py_func.__qualname__, self._py_func.__module__ or _dynamic_modname, args
                    if (fndesc.qualname, fndesc.modname, tuple(signature.args)) != expected:
                        raise TypeError(f"an entry of {fndesc.modname}.{fndesc.qualname}{tuple(signature.args)}")
                    return self._impl.rebuild(target_context, data)
                except Exception as exc:  # noqa: BLE001 - a foreign or damaged payload fails in many ways
                    set_aside(*reader.last_data, exc)
            return None

    from numba.core import event as _event
    from numba.core.compiler_lock import global_compiler_lock as _compiler_lock
    from numba.core.registry import CPUDispatcher

    class _Dispatcher(CPUDispatcher):
        """numba's dispatcher of a kernel, made cheaper to compile for other kernels.

        * Typed from another kernel with its arguments' plain types: a constant argument (``mat(table, base, 4)``)
          does not compile one specialisation per value.
        * Compiled for another kernel without numba's Python wrapper (which numba otherwise builds, optimises and
          caches for every signature: about a sixth of a first run's compile time).  Such a signature is never
          offered to Python calls: a Python call with it compiles (or loads) it again, wrapper included.  Its
          cache entry is kept apart from the wrapped one (:meth:`_GuardedCache._index_key`).
        """

        _for_kernels = 0
        """While above 0, this dispatcher is being typed from another kernel (:meth:`get_call_template`)."""

        def __init__(self, *args, **kwargs) -> None:
            super().__init__(*args, **kwargs)
            self.kernels_only: set[tuple] = set()
            """The signatures compiled (or loaded) without the Python wrapper."""

        def get_call_template(self, args, kws):
            plain = numba.types.unliteral
            with _compiler_lock:
                self._for_kernels += 1
                try:
                    return super().get_call_template(tuple(map(plain, args)), {k: plain(v) for k, v in kws.items()})
                finally:
                    self._for_kernels -= 1

        def compile(self, sig):
            with _compiler_lock:
                wrapperless = self._for_kernels > 0
                args = tuple(_sigutils.normalize_signature(sig)[0])
                if not wrapperless and args in self.kernels_only:
                    del self.overloads[args]  # compiled for kernels only: a Python call needs the wrapper
                    self.kernels_only.discard(args)
                saved = self.targetoptions.get("no_cpython_wrapper", False), getattr(self._cache, "wrapperless", False)
                self.targetoptions["no_cpython_wrapper"] = self._cache.wrapperless = wrapperless
                try:
                    return super().compile(sig)
                finally:
                    self.targetoptions["no_cpython_wrapper"], self._cache.wrapperless = saved

        def add_overload(self, cres):
            if self.targetoptions.get("no_cpython_wrapper"):  # kept out of the table Python calls are matched in
                self.overloads[tuple(cres.signature.args)] = cres
                self.kernels_only.add(tuple(cres.signature.args))
            else:
                super().add_overload(cres)

    class _Watcher(_event.Listener):
        """Calls ``callback(dispatcher)`` when numba starts compiling a signature of one of :data:`KERNELS`."""

        def __init__(self, callback: Callable[[object], None]) -> None:
            self.callback = callback

        def on_start(self, ev) -> None:
            kernel = ev.data["dispatcher"]
            if id(kernel) in _KERNEL_IDS:
                self.callback(kernel)

        def on_end(self, ev) -> None:
            pass


COMPILE_OPTIONS = {"nopython": True, "no_cfunc_wrapper": True}
"""numba's options for every kernel: no C-callable wrapper (kernels are called from Python and from other
kernels only), which numba would otherwise build for every kernel and every signature."""


def compiled(function: Callable, nogil: bool = False, counted: bool = True) -> Callable:
    """``numba.njit(cache=True)(function)`` cached in :data:`cache_dir` and registered in :data:`KERNELS`;
    ``function`` itself without numba.  Where no folder can be written at all, the kernel is compiled
    in every process (uncached) and a warning is logged.  A cache entry that cannot be read back
    (truncated, garbage, another function's) is set aside with a one-line warning and compiled again.
    ``nogil``: the kernel releases the GIL while it runs (several threads may run it at once).

    To keep the first run short, a kernel compiles for its arguments' plain types when another kernel
    calls it (one signature for ``f(a, 4)`` and ``f(a, 5)``) and gets no C-callable wrapper
    (:data:`COMPILE_OPTIONS`).

    ``counted=False`` (:func:`uncounted`): the kernel keeps no reference counts.  numba otherwise counts a
    reference to every array a kernel receives or makes (each member of a tuple of arrays too) with a call at its
    start and end, around every call that passes arrays on, which costs more than the arithmetic of a small robot.
    Such a kernel allocates nothing and returns no array (numba refuses to compile one that does); the arrays it
    receives are kept alive by its caller.  Every other kernel counts them (set explicitly: a kernel called from an
    uncounted one would otherwise inherit the setting)."""
    if not available:
        return function
    kernel = _Dispatcher(py_func=function, locals={},
                         targetoptions={**COMPILE_OPTIONS, "nogil": nogil, "_nrt": counted})
    previous = numba.config.CACHE_DIR
    numba.config.CACHE_DIR = cache_dir  # read by numba when the cache picks its folder
    try:
        kernel._cache = _GuardedCache(function)  # what numba.njit(cache=True) sets, reading through the guard
    except RuntimeError as exc:  # numba found no writable cache folder
        logger.warning("%s: compiled in every process, not cached (%s)", function.__qualname__, exc)
    finally:
        numba.config.CACHE_DIR = previous
    KERNELS.append(kernel)
    _KERNEL_IDS.add(id(kernel))
    return kernel


def uncounted(function: Callable, nogil: bool = False) -> Callable:
    """:func:`compiled` with ``counted=False``: a kernel that keeps no reference counts (it allocates nothing and
    returns no array)."""
    return compiled(function, nogil=nogil, counted=False)


def _pointer_intrinsic(element: str) -> Callable:
    """A numba intrinsic turning an integer address into an ``element*`` pointer (for ``numba.carray``), so
    that a kernel reads arrays listed by address.  The caller keeps those arrays alive."""

    def pointer(typingctx, address):
        signature = numba.types.CPointer(getattr(numba.types, element))(address)

        def codegen(context, builder, sig, args):
            return builder.inttoptr(args[0], context.get_value_type(sig.return_type))

        return signature, codegen

    pointer.__name__ = f"{element}_pointer"
    return numba.extending.intrinsic(pointer) if available else pointer


float64_pointer = _pointer_intrinsic("float64")
int64_pointer = _pointer_intrinsic("int64")

C_ARGUMENTS = 7
"""The arguments of a C callback (:func:`c_callback`, :func:`call_address`): seven addresses."""


def _call_address(typingctx, function, a1, a2, a3, a4, a5, a6, a7):
    """``function(a1, ..., a7)``: call the C function at integer address ``function`` with seven addresses (a
    ``void f(void*, ..., void*)``), from a kernel; the caller keeps the function and the arrays alive."""
    signature = numba.types.void(function, a1, a2, a3, a4, a5, a6, a7)

    def codegen(context, builder, sig, args):
        from llvmlite import ir

        pointer = ir.IntType(8).as_pointer()
        callee = builder.inttoptr(args[0], ir.FunctionType(ir.VoidType(), [pointer] * C_ARGUMENTS).as_pointer())
        builder.call(callee, [builder.inttoptr(a, pointer) for a in args[1:]])
        return context.get_dummy_value()

    return signature, codegen


call_address = numba.extending.intrinsic(_call_address) if available else None


def c_callback(function: Callable) -> tuple[int, object]:
    """``(address, keep)``: ``function(a1, ..., a7)`` (seven int64 addresses, e.g. a wrapper that turns them into
    arrays with :func:`vector_at`/:func:`matrix_at`) compiled as a C callback for :func:`call_address`; ``keep``
    must stay alive while the address is used.  Compiled once per process (not cached on disk)."""
    signature = numba.types.void(*([numba.types.int64] * C_ARGUMENTS))
    callback = numba.cfunc(signature)(function)
    return callback.address, callback


def jit(function: Callable) -> Callable:
    """``numba.njit(function)`` (not cached: a user's function), or ``function`` without numba."""
    return numba.njit(function) if available else function


def _address(array):
    return array.ctypes.data


address = compiled(_address)
"""``address(array)``: the address of ``array``'s first element (for :func:`float64_pointer`/:func:`int64_pointer`),
a quarter of the cost of ``array.ctypes.data`` from Python."""


def checked_address(array: np.ndarray) -> int:
    """:func:`address` of a C-contiguous float64 or int64 array; TypeError for any other array."""
    if not array.flags.c_contiguous or array.dtype not in (np.float64, np.int64):
        raise TypeError(f"compiled kernel: an array of dtype {array.dtype} that is not C-contiguous")
    return address(array)


def _matrix_at(address, n, m):
    """The C-contiguous ``(n, m)`` float64 array at ``address`` (kept alive by the caller)."""
    return carray(float64_pointer(address), (n, m))


def _vector_at(address, n):
    """The float64 vector of length ``n`` at ``address`` (kept alive by the caller)."""
    return carray(float64_pointer(address), (n,))


matrix_at = compiled(_matrix_at)
vector_at = compiled(_vector_at)
carray = numba.carray if available else None


def is_cached(kernel: object) -> bool:
    """True when numba's on-disk cache (or :data:`SHIPPED_DIR`) holds a usable index for ``kernel``: one written
    by this numba for the kernel's current source, listing at least one compiled signature.  Nothing is compiled
    or loaded; a dispatcher without a cache counts as not cached."""
    cache = getattr(kernel, "_cache", None)
    for index in getattr(cache, "readers", ()):
        try:
            if index._load_index():
                return True
        except Exception:  # noqa: BLE001 - whatever makes the index unreadable makes the cache unusable
            pass
    return False


def cache_is_cold(kernels: Iterable[object] | None = None) -> bool:
    """True when some kernel (default: every one in :data:`KERNELS`) is not :func:`is_cached`, i.e. the
    first solve will compile.  False without numba."""
    return available and not all(is_cached(k) for k in (KERNELS if kernels is None else kernels))


@contextlib.contextmanager
def watch_compilations(callback: Callable[[object], None]) -> Iterator[None]:
    """Inside the block, ``callback(kernel)`` is called whenever numba starts compiling a signature of one of
    :data:`KERNELS` (never when it loads one from its on-disk cache); without numba, never."""
    if not available:
        yield
        return
    watcher = _Watcher(callback)
    _event.register("numba:compile", watcher)
    try:
        yield
    finally:
        _event.unregister("numba:compile", watcher)


def kernel_callees(kernel: object) -> list:
    """The kernels of :data:`KERNELS` that ``kernel``'s source names (as a global or ``module.name``): those
    numba compiles with it unless they are cached."""
    function = getattr(kernel, "py_func", None)
    if function is None:
        return []
    names, codes = set(), [function.__code__]
    while codes:
        code = codes.pop()
        names.update(code.co_names)
        codes += [c for c in code.co_consts if hasattr(c, "co_names")]
    found = {}
    for name in names:
        value = function.__globals__.get(name)
        candidates = [getattr(value, n, None) for n in names] if inspect.ismodule(value) else [value]
        found.update((id(c), c) for c in candidates if id(c) in _KERNEL_IDS and c is not kernel)
    return list(found.values())


def kernels_enabled() -> bool:
    """True when the library runs its compiled kernels (numba installed and not switched off)."""
    return active


def set_kernels(enabled: bool) -> None:
    """Switch the compiled kernels on or off for the whole library.

    Raises
    ------
    TypeError
        If ``enabled`` is not a bool.
    RuntimeError
        If ``enabled`` is True and numba is not installed.
    """
    global active
    if not isinstance(enabled, (bool, np.bool_)):
        raise TypeError(f"enabled must be a bool, got {type(enabled).__name__}")
    if enabled and not available:
        raise RuntimeError("crocopy.set_kernels(True): numba is not installed (pip install numba)")
    active = bool(enabled)


@contextlib.contextmanager
def use_kernels(enabled: bool) -> Iterator[None]:
    """Context manager: ``set_kernels(enabled)`` inside the block, the previous setting after it."""
    global active
    previous = active
    set_kernels(enabled)
    try:
        yield
    finally:
        active = previous


def overridden(obj: object, owner: type, steps: Iterable[str]) -> list[str]:
    """The names in ``steps`` that ``type(obj)`` defines differently from ``owner``."""
    cls = type(obj)
    return [step for step in steps if getattr(cls, step) is not getattr(owner, step)]


def log_fallback(cls: type, steps: Iterable[str], kernel: str, how: str = "overrides") -> None:
    """Log once per ``(cls, step)``, at DEBUG level, that ``cls`` ``how`` ``steps`` and so skips ``kernel``."""
    new = [step for step in steps if (cls, step) not in _logged]
    if not new:
        return
    _logged.update((cls, step) for step in new)
    logger.debug(
        "%s %s %s: %s is not used for it, the numpy/Python steps run instead",
        cls.__qualname__, how, ", ".join(new), kernel,
    )
