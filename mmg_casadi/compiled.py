"""Compile CasADi Functions to native code once and cache the shared library on disk.

A Function is code-generated to C, the source hashed (SHA-256 of the C text and the compiler flags), and
compiled with the system C compiler to ``<cache>/<name>_<hash>.so``; later calls (in this or any other process,
e.g. a worker of the Monte Carlo pool) load that library with ``casadi.external`` instead of recompiling.
The cache directory is ``$MMG_CASADI_CACHE`` or ``~/.cache/mmg-casadi``, created private to the user (mode 0700);
a cache directory, or a library in it, that another user owns or that others may write to is refused
(:class:`CacheError`), since loading a library runs its code.

Every library this module builds has a record ``<name>_<hash>.so.sha256`` (the SHA-256 of the library's bytes,
written before the library is renamed into place); a cached library is loaded only if it is complete
(:func:`library_is_complete`) and matches its record (:func:`library_is_trusted`), else it is rebuilt (a library
without a record, or that differs from it, is never loaded; a mismatch is reported with a warning).

The compiler never outlives the process that started it: it runs under a small watchdog process
(``mmg_casadi/_watchdog.py``, mode ``build``) that sits in a process group of its own, outside the study's, so
that a signal to the study's whole group (``kill -KILL -- -PGID``, what ``kill -9 %1`` does in a shell) leaves it
alive to clean up. The watchdog kills the compiler (``gcc`` with its ``cc1``, ``as``, ``ld``, in one process group
of their own) when the compiling process is interrupted (Ctrl-C, SIGTERM, SIGHUP: the compiling process tells it)
or dies, also by SIGKILL (the watchdog sees itself re-parented within 0.05 s). ``gcc`` is tied to the watchdog by
``prctl(PR_SET_PDEATHSIG, SIGKILL)`` and the watchdog is a child subreaper, so a compiler process whose parent
died is still found and killed. The build happens in a folder ``<cache>/.build-<pid>-<random>@<host>`` that the
watchdog removes in every case; a folder left by a process that is gone (e.g. after a power cut, or a SIGKILL of
the watchdog itself) is removed the first time a process of this host uses the cache. The library is flushed to
disk and renamed into place atomically.
"""

from __future__ import annotations

import hashlib
import os
import secrets
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import casadi as ca

from mmg_casadi.errors import InputError

DEFAULT_FLAGS = ("-O2", "-fno-math-errno", "-fPIC", "-shared")
"""C compiler flags. ``-fno-math-errno`` lets ``sqrt`` compile to one instruction (errno is never read; the
values are the same); no ``-ffast-math`` / ``-march=native``, which change results in the last bits."""
BUILD_PREFIX = ".build-"
"""Name prefix of the temporary build folders in the cache (``.build-<pid>-<random>@<host>``)."""
WATCHDOG = Path(__file__).with_name("_watchdog.py")
"""The watchdog script the compiler runs under."""
STOP_TIMEOUT = 10.0
"""Seconds to wait for the watchdog to stop the compiler and remove the build folder after an interruption."""
RECORD_SUFFIX = ".sha256"
"""Suffix of a library's hash record (``<library>.so.sha256``: the hexadecimal SHA-256 of the library)."""

NOTICES = {"stream": None}
"""Where :func:`compile_function` says that it compiles (one line per library: what, then the seconds it took): a
file, ``"stderr"`` (whatever ``sys.stderr`` is at the time), or ``None`` for silence (the default of the library;
the command line sets ``"stderr"`` unless ``--quiet``). Nothing is said when the library is cached."""

_SWEPT: set[Path] = set()
"""Cache directories whose stale build folders this process has removed (once per process)."""
_TRUSTED: dict[Path, tuple] = {}
"""Libraries this process has checked against their records, with the (device, inode, size, mtime) checked."""


class CacheError(InputError):
    """The compile cache (``$MMG_CASADI_CACHE``) is not private to the user, so its libraries cannot be trusted.

    Parameters
    ----------
    field, allowed, got
        As for :class:`~mmg_casadi.errors.InputError`.
    """


def cache_dir() -> Path:
    """Directory holding compiled libraries (created on demand, private to the user: mode 0700).

    An existing directory of the user that others may read or enter is made private (``chmod 700``); one that
    another user owns, or a symbolic link, is refused. The first call of a process removes the build folders
    that processes of this host left behind (module notes).

    Returns
    -------
    pathlib.Path
        ``$MMG_CASADI_CACHE`` if set, else ``~/.cache/mmg-casadi``.

    Raises
    ------
    CacheError
        The directory is owned by another user, is a symbolic link, or cannot be created.
    """
    d = Path(os.environ.get("MMG_CASADI_CACHE", Path.home() / ".cache" / "mmg-casadi"))
    try:
        d.parent.mkdir(parents=True, exist_ok=True)
        d.mkdir(mode=0o700, exist_ok=True)
        st = os.lstat(d)
    except OSError as err:
        raise CacheError("MMG_CASADI_CACHE", f"a directory that can be created ({err.strerror or err})",
                         str(d)) from None
    if not os.path.isdir(d) or os.path.islink(d):
        raise CacheError("MMG_CASADI_CACHE", "a directory (not a symbolic link or a file)", str(d))
    if hasattr(os, "getuid") and st.st_uid != os.getuid():
        raise CacheError("MMG_CASADI_CACHE", f"a directory owned by you (uid {os.getuid()}), since its libraries "
                         f"are loaded as code; this one belongs to uid {st.st_uid}", str(d))
    if st.st_mode & 0o077:
        os.chmod(d, 0o700)
    if d not in _SWEPT:
        _SWEPT.add(d)
        _remove_stale_builds(d)
    return d


def _compiler() -> str:
    cc = os.environ.get("CC") or shutil.which("gcc") or shutil.which("cc") or shutil.which("clang")
    if not cc:
        raise RuntimeError("no C compiler found (set CC); mmg-casadi compiles its closed-loop steps to native code")
    return cc


def generate_source(f: ca.Function, also=()) -> str:
    """C source of ``f`` (and its dependencies) as generated by CasADi.

    Parameters
    ----------
    f : casadi.Function
        Function to generate C code for.
    also : sequence of casadi.Function, optional
        Further Functions exported by the same source (code they share with ``f`` is generated once).

    Returns
    -------
    str
        The C source.
    """
    with tempfile.TemporaryDirectory() as tmp:
        cg = ca.CodeGenerator(f"{f.name()}.c", {"with_header": False, "casadi_int": "long long int"})
        for g in (f, *also):
            cg.add(g)
        cg.generate(tmp + os.sep)
        return Path(tmp, f"{f.name()}.c").read_text()


def library_path(f: ca.Function, flags=DEFAULT_FLAGS, also=()) -> tuple[Path, str]:
    """Cache path for ``f`` compiled with ``flags`` and the C source it is built from.

    Parameters
    ----------
    f : casadi.Function
        Function to compile.
    flags : sequence of str, optional
        C compiler flags; they are part of the cache key.
    also : sequence of casadi.Function, optional
        Further Functions in the same library (:func:`generate_source`).

    Returns
    -------
    path : pathlib.Path
        ``<cache_dir>/<name>_<key>.so``, ``key`` a hash of the source, the flags and the CasADi version.
    source : str
        The C source (:func:`generate_source`).
    """
    src = generate_source(f, also)
    key = hashlib.sha256((src + "\0" + " ".join(flags) + "\0" + ca.__version__).encode()).hexdigest()[:16]
    return cache_dir() / f"{f.name()}_{key}.so", src


def compile_function(f: ca.Function, flags=DEFAULT_FLAGS, also=(), *, label: str | None = None):
    """Return a natively compiled equivalent of ``f``, compiling only when the cache has no library for it.

    With ``also``, one library holds ``f`` and those Functions (their shared code compiled once) and the
    compiled equivalents of all of them are returned, in order, as a list.

    The library is built in a temporary folder by a compiler that dies with this process (module notes) and moved
    into place atomically, so concurrent processes that compile the same Function never load a half-written file;
    a cached library that is not complete (:func:`library_is_complete`) is rebuilt.

    Parameters
    ----------
    f : casadi.Function
        Function to compile.
    flags : sequence of str, optional
        C compiler flags passed to the compiler.
    also : sequence of casadi.Function, optional
        Further Functions to compile into the same library.
    label : str, optional
        What is compiled, in words, for the notice of :data:`NOTICES` (default: the Function's name).

    Returns
    -------
    casadi.Function or list of casadi.Function
        The compiled Function (``casadi.external``), or with ``also`` one per Function, ``f`` first.

    Examples
    --------
    >>> x = ca.SX.sym("x")
    >>> g = compile_function(ca.Function("square_plus_one", [x], [x**2 + 1]))
    >>> float(g(3.0))
    10.0
    """
    so, src = library_path(f, flags, also)
    if not library_is_trusted(so):
        stream = sys.stderr if NOTICES["stream"] == "stderr" else NOTICES["stream"]
        if stream is not None:
            print(f"compiling {label or f.name()} … ", end="", file=stream, flush=True)
        t0 = time.perf_counter()
        try:
            _build(f.name(), src, so, flags)
        except BaseException:
            if stream is not None:
                print("stopped", file=stream, flush=True)
            raise
        if stream is not None:
            print(f"{time.perf_counter() - t0:.0f} s (cached for next time)", file=stream, flush=True)
    compiled = load_library(so, [g.name() for g in (f, *also)])
    return compiled if also else compiled[0]


def load_library(so, names) -> list:
    """The Functions ``names`` of the cached library ``so``, which must be trusted (:func:`library_is_trusted`).

    Parameters
    ----------
    so : str or Path
        The library (e.g. from :func:`library_path`).
    names : sequence of str
        Names of the Functions to load from it.

    Returns
    -------
    list of casadi.Function
        One ``casadi.external`` per name.

    Raises
    ------
    RuntimeError
        The library is missing, incomplete, foreign or does not match its record.
    """
    if not library_is_trusted(so):
        raise RuntimeError(f"the library {so} is missing or does not match its record {so}{RECORD_SUFFIX} "
                           "(another process replaced it?)")
    return [ca.external(n, str(so)) for n in names]


def library_is_trusted(path) -> bool:
    """Whether the cached library at ``path`` may be loaded: it is complete (:func:`library_is_complete`), owned
    by this user and writable by nobody else, and its bytes match its record ``path + ".sha256"`` (written when
    :func:`compile_function` built it). A library that differs from its record is reported with a
    ``RuntimeWarning`` (it was modified, or replaced, after it was built) and its record removed.

    A library checked once by this process is not hashed again while its size and time stamps are unchanged.

    Parameters
    ----------
    path : str or Path
        The library file.

    Returns
    -------
    bool
        False for a missing, incomplete, foreign or unrecorded library, or one that does not match its record.

    Examples
    --------
    >>> x = ca.SX.sym("x")
    >>> so, _ = library_path(ca.Function("square_plus_two", [x], [x**2 + 2]))
    >>> _ = compile_function(ca.Function("square_plus_two", [x], [x**2 + 2]))
    >>> library_is_trusted(so), Path(str(so) + RECORD_SUFFIX).read_text().strip() == _sha256(so)
    (True, True)
    """
    path = Path(path)
    record = Path(str(path) + RECORD_SUFFIX)
    try:
        st, sr = os.stat(path), os.stat(record)  # no record: e.g. built by an older version, rebuilt once
    except OSError:
        return False
    stamp = tuple((s.st_dev, s.st_ino, s.st_size, s.st_mtime_ns, s.st_ctime_ns) for s in (st, sr))
    if _TRUSTED.get(path) == stamp:
        return True
    if any((hasattr(os, "getuid") and s.st_uid != os.getuid()) or s.st_mode & 0o022 for s in (st, sr)):
        return False
    if not library_is_complete(path):
        return False
    try:
        expected = record.read_text(encoding="ascii").strip()
    except (OSError, UnicodeDecodeError):
        return False
    if _sha256(path) != expected:
        import warnings
        warnings.warn(f"the compiled library {path} does not match the hash recorded when it was built; it is not "
                      "loaded but rebuilt", RuntimeWarning, stacklevel=2)
        record.unlink(missing_ok=True)
        return False
    _TRUSTED[path] = stamp
    return True


def _sha256(path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _build(name: str, src: str, so: Path, flags) -> None:
    """Compile ``src`` to ``so`` under the watchdog (module notes); on an interruption stop it, then re-raise."""
    build = so.parent / f"{BUILD_PREFIX}{os.getpid()}-{secrets.token_hex(4)}@{socket.gethostname()}"
    c_file, out = f"{name}.c", so.name
    # relative names, run in the build folder: the library's bytes do not depend on the folder's random name
    cmd = [sys.executable, "-I", "-S", str(WATCHDOG), "build", str(os.getpid()), str(build), c_file, out, str(so),
           "--", _compiler(), *flags, c_file, "-o", out, "-lm"]
    # a process group of its own: a signal to the study's group (kill -9 %1) must leave it alive to clean up
    guard = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                             process_group=0)
    try:
        _out, err = guard.communicate(src.encode())
    except BaseException:  # Ctrl-C, SIGTERM (raised by signals.terminate_as_interrupt), ...
        guard.send_signal(signal.SIGTERM)
        try:
            guard.wait(STOP_TIMEOUT)
        except subprocess.TimeoutExpired:
            guard.kill()
            guard.wait()
            shutil.rmtree(build, ignore_errors=True)
        raise
    if guard.returncode != 0:
        raise RuntimeError(f"compiling {name} failed:\n{err.decode(errors='replace')[-2000:]}")


def _remove_stale_builds(directory: Path) -> None:
    """Remove the build folders in ``directory`` of processes of this host that are gone."""
    host = socket.gethostname()
    for d in directory.glob(BUILD_PREFIX + "*"):
        head, _, owner_host = d.name[len(BUILD_PREFIX):].partition("@")
        pid = head.split("-")[0]
        if owner_host == host and pid.isdigit() and not _alive(int(pid)):
            shutil.rmtree(d, ignore_errors=True)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def library_is_complete(path) -> bool:
    """Whether the shared library at ``path`` is whole: for an ELF file (Linux), every segment and the section
    header table lie within the file; elsewhere, the file is not empty.

    ``dlopen`` of a library cut short (e.g. by a crash while it was written) can crash the process instead of
    failing, so :func:`compile_function` checks a cached library with this before loading it.

    Parameters
    ----------
    path : str or Path
        The library file.

    Returns
    -------
    bool
        False for a missing, empty or truncated file (or an ELF header that does not parse).

    Examples
    --------
    >>> x = ca.SX.sym("x")
    >>> so, _ = library_path(ca.Function("square_plus_one", [x], [x**2 + 1]))
    >>> _ = compile_function(ca.Function("square_plus_one", [x], [x**2 + 1]))
    >>> library_is_complete(so), library_is_complete(so.with_suffix(".missing"))
    (True, False)
    """
    try:
        with open(path, "rb") as fh:
            head = fh.read(64)
            size = os.fstat(fh.fileno()).st_size
            if head[:4] != b"\x7fELF":
                return size > 0 and not sys.platform.startswith("linux")
            wide, order = head[4] == 2, "<" if head[5] == 1 else ">"
            if wide:
                phoff, shoff = struct.unpack_from(order + "QQ", head, 32)
                phentsize, phnum, shentsize, shnum = struct.unpack_from(order + "HHHH", head, 54)
                seg = order + "8xQ16xQ"  # p_type, p_flags, p_offset, p_vaddr, p_paddr, p_filesz
            else:
                phoff, shoff = struct.unpack_from(order + "II", head, 28)
                phentsize, phnum, shentsize, shnum = struct.unpack_from(order + "HHHH", head, 42)
                seg = order + "4xI8xI"  # p_type, p_offset, p_vaddr, p_paddr, p_filesz
            end = max(phoff + phentsize * phnum, shoff + shentsize * shnum)
            fh.seek(phoff)
            table = fh.read(phentsize * phnum)
            if len(table) < phentsize * phnum:
                return False
            for k in range(phnum):
                offset, filesz = struct.unpack_from(seg, table, k * phentsize)
                end = max(end, offset + filesz)
            return size >= end
    except (OSError, struct.error):
        return False
