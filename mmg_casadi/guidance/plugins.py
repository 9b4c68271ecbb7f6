"""Methods from outside the package: plugin modules and files, installed plugins, and shipping them to workers.

A plugin is a Python module that registers one or more methods when it is imported
(:func:`mmg_casadi.guidance.methods.register`; the how-to "Write your own method" has one). It comes in two ways:

* ``--plugin FILE.py`` or ``--plugin package.module`` on the command line (repeatable; every command that runs
  methods takes it), or :func:`load` in Python;
* an installed package that declares an entry point in the group ``mmg_casadi.methods`` (:data:`ENTRY_POINTS`)::

      [project.entry-points."mmg_casadi.methods"]
      my-method = "my_package.my_method"        # a module that registers when imported
      # or "my_package.my_method:METHOD"        # a Method (or a list of them) that the loader registers

  The command line loads every installed plugin when it starts, the Python API the first time it looks up a name
  that is not registered (:func:`mmg_casadi.guidance.methods.names`), or at
  :func:`~mmg_casadi.guidance.methods.load_installed`.

A name that is already registered is refused with one line naming the plugin (exit status 2 on the command line);
loading the same plugin twice registers nothing the second time.

Workers: a forked local worker inherits the registry; a Ray worker (another process, possibly another machine)
receives the plugins with each batch (:func:`sources`: the module name and the text of the file it was loaded
from) and loads them before running it (:func:`ensure`): from the same file if it can read it, else from the
shipped text under the same module name, so the worker builds the same compiled step (the disk cache is keyed by
the generated C source).
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.metadata
import importlib.util
import sys
from dataclasses import dataclass
from pathlib import Path

from mmg_casadi.errors import InputError
from mmg_casadi.guidance import methods

ENTRY_POINTS = methods.ENTRY_POINTS
"""The entry-point group of installed plugins."""
load_installed = methods.load_installed

FIELD = "--plugin"
"""Field named by the errors of :func:`load`."""


@dataclass(frozen=True)
class PluginSource:
    """A loaded plugin as a worker needs it.

    Parameters
    ----------
    spec : str
        What the user gave: a file path or a module name (for an installed plugin, ``"entry point NAME"``).
    module : str
        The name of the module it was loaded as (in :data:`sys.modules`).
    path : str or None
        The absolute path of the file it was read from (None if it has none, e.g. a namespace package).
    text : str or None
        The file's text (None without a file).
    methods : tuple of str
        The methods it registered.
    """

    spec: str
    module: str
    path: str | None
    text: str | None
    methods: tuple = ()


_LOADED: dict[str, PluginSource] = {}
"""Plugins loaded from ``--plugin`` or :func:`load`, by module name, in loading order."""


def _module_name(path: Path) -> str:
    """A module name of its own for a plugin file (stem and a hash of the absolute path)."""
    stem = "".join(c if c.isalnum() else "_" for c in path.stem)
    return f"mmg_casadi_plugin_{stem}_{hashlib.sha256(str(path).encode()).hexdigest()[:8]}"


def _is_file_spec(spec: str) -> bool:
    return spec.endswith(".py") or "/" in spec or "\\" in spec or Path(spec).is_file()


def load(spec, *, field: str = FIELD) -> tuple[str, ...]:
    """Load the plugin ``spec`` (a ``.py`` file or an importable module name); returns the methods it registered.

    Parameters
    ----------
    spec : str or path-like
        A Python file, or the dotted name of an importable module, whose import registers methods.
    field : str, default '--plugin'
        Field named in an error.

    Returns
    -------
    tuple of str
        The names it registered (empty if it was loaded before).

    Raises
    ------
    InputError
        The file or module does not exist or fails to import (the error's type and message on one line), or a
        name it registers is taken.

    Examples
    --------
    >>> load("no_such_module_xyz")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: --plugin: expected a Python file or an importable module that registers methods (ModuleNotFoundError: ...), got 'no_such_module_xyz'
    """
    spec = str(spec)
    if _is_file_spec(spec):
        path = Path(spec).expanduser().resolve()
        if not path.is_file():
            raise InputError(field, "a Python file or an importable module that registers methods (no such file)",
                             spec)
        name = _module_name(path)
        if name in _LOADED:
            return ()
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as err:
            raise InputError(field, f"a readable UTF-8 Python file ({err})", spec) from None
        return _run(spec, name, str(path), text, field)
    if spec in _LOADED:
        return ()
    before = tuple(methods.METHODS)
    try:
        mod = importlib.import_module(spec)
    except InputError as err:
        raise InputError(f"{field} {spec}: {err.field}", err.allowed, err.got) from None
    except Exception as err:  # noqa: BLE001 - a plugin's own failure, reported on one line
        raise InputError(field, "a Python file or an importable module that registers methods "
                         f"({type(err).__name__}: {err})", spec) from None
    path = getattr(mod, "__file__", None)
    text = Path(path).read_text(encoding="utf-8") if path and Path(path).is_file() else None
    added = tuple(n for n in methods.METHODS if n not in before)
    _LOADED[spec] = PluginSource(spec, spec, path, text, added)
    return added


def _run(spec: str, name: str, path: str | None, text: str, field: str) -> tuple[str, ...]:
    """Execute a plugin's text as module ``name`` (registered in :data:`sys.modules`, so its functions pickle by
    reference in forked workers); on failure the module and whatever it registered are removed."""
    before = tuple(methods.METHODS)
    mod_spec = importlib.util.spec_from_loader(name, loader=None, origin=path)
    mod = importlib.util.module_from_spec(mod_spec)
    mod.__file__ = path
    sys.modules[name] = mod
    try:
        exec(compile(text, path or name, "exec"), mod.__dict__)  # noqa: S102 - loading a plugin is running it
    except BaseException as err:
        sys.modules.pop(name, None)
        for n in methods.METHODS.keys() - set(before):
            methods.unregister(n)
        if isinstance(err, InputError):
            raise InputError(f"{field} {spec}: {err.field}", err.allowed, err.got) from None
        if not isinstance(err, Exception):
            raise
        raise InputError(field, "a Python file or an importable module that registers methods "
                         f"({type(err).__name__}: {err})", spec) from None
    added = tuple(n for n in methods.METHODS if n not in before)
    _LOADED[name] = PluginSource(spec, name, path, text, added)
    return added


def sources() -> tuple[PluginSource, ...]:
    """The plugins loaded in this process from ``--plugin`` or :func:`load`, as workers need them.

    Returns
    -------
    tuple of PluginSource
        In loading order (installed plugins are not listed: a worker loads them itself, :func:`ensure`).
    """
    return tuple(_LOADED.values())


def ensure(shipped) -> None:
    """Load, in a worker, the plugins the parent process had (:func:`sources`) and the installed ones.

    A plugin already loaded (a forked worker, a reused Ray worker) is skipped. A file plugin runs from the shipped
    text (the worker need not see the file); a module plugin is imported, else run from the shipped text of its
    file.

    Parameters
    ----------
    shipped : iterable of PluginSource
        The parent's :func:`sources`.
    """
    methods.load_installed()
    for s in shipped:
        if s.module in _LOADED or s.spec in _LOADED or all(m in methods.METHODS for m in s.methods):
            continue
        if s.module != s.spec:  # a file
            _run(s.spec, s.module, s.path, s.text, FIELD)
            continue
        try:
            load(s.spec)
        except InputError:
            if s.text is None:
                raise
            _run(s.spec, s.module, s.path, s.text, FIELD)
