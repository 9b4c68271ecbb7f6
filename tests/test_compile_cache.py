"""The compile cache loads only libraries it built itself: private folder, hash record, foreign files refused."""

from __future__ import annotations

import os
import stat
import sys
import warnings
from pathlib import Path

import casadi as ca
import pytest

from mmg_casadi.compiled import (RECORD_SUFFIX, CacheError, _sha256, cache_dir, compile_function,
                                 library_is_trusted, library_path)

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="POSIX owners and modes")


def _square(name: str) -> ca.Function:
    x = ca.SX.sym("x")
    return ca.Function(name, [x], [x**2 + 1])


def test_the_cache_folder_is_created_private_and_an_open_one_is_made_private(tmp_path, monkeypatch):
    monkeypatch.setenv("MMG_CASADI_CACHE", str(tmp_path / "new" / "cache"))
    d = cache_dir()
    assert stat.S_IMODE(d.stat().st_mode) == 0o700
    open_one = tmp_path / "open"
    open_one.mkdir(mode=0o777)
    os.chmod(open_one, 0o777)  # the umask may have taken bits away
    monkeypatch.setenv("MMG_CASADI_CACHE", str(open_one))
    assert stat.S_IMODE(cache_dir().stat().st_mode) == 0o700


def test_a_cache_folder_that_is_a_link_or_belongs_to_another_user_is_refused(tmp_path, monkeypatch):
    target = tmp_path / "target"
    target.mkdir(mode=0o700)
    link = tmp_path / "link"
    link.symlink_to(target)
    monkeypatch.setenv("MMG_CASADI_CACHE", str(link))
    with pytest.raises(CacheError, match="MMG_CASADI_CACHE: expected a directory \\(not a symbolic link"):
        cache_dir()
    if os.getuid() != 0:
        return  # only root can give a folder to another user
    foreign = tmp_path / "foreign"
    foreign.mkdir(mode=0o700)
    os.chown(foreign, 65534, 65534)
    monkeypatch.setenv("MMG_CASADI_CACHE", str(foreign))
    with pytest.raises(CacheError, match="owned by you"):
        cache_dir()


def test_a_library_is_recorded_and_a_modified_one_is_refused_and_rebuilt(tmp_path, monkeypatch):
    monkeypatch.setenv("MMG_CASADI_CACHE", str(tmp_path))
    f = _square("tampered_square")
    compile_function(f)
    so, _src = library_path(f)
    record = Path(str(so) + RECORD_SUFFIX)
    whole = so.read_bytes()
    assert record.read_text().strip() == _sha256(so) and library_is_trusted(so)
    # another library of the same size and name, complete (loading it would run its code)
    other = _square("tampered_squarX")
    compile_function(other)
    fake = library_path(other)[0].read_bytes()
    tmp = tmp_path / "fake"
    tmp.write_bytes(fake)
    os.replace(tmp, so)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert not library_is_trusted(so)
    assert any("does not match the hash recorded" in str(w.message) for w in caught)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        g = compile_function(f)
    assert so.read_bytes() == whole and float(g(3.0)) == 10.0
    assert record.read_text().strip() == _sha256(so)


def test_a_library_without_record_or_writable_by_others_is_rebuilt_not_loaded(tmp_path, monkeypatch):
    monkeypatch.setenv("MMG_CASADI_CACHE", str(tmp_path))
    f = _square("unrecorded_square")
    compile_function(f)
    so, _src = library_path(f)
    Path(str(so) + RECORD_SUFFIX).unlink()  # e.g. built by an older version
    assert not library_is_trusted(so)
    inode = so.stat().st_ino
    compile_function(f)
    assert so.stat().st_ino != inode and library_is_trusted(so)  # a new file, recorded
    os.chmod(so, 0o777)
    assert not library_is_trusted(so)
    compile_function(f)
    assert library_is_trusted(so) and not so.stat().st_mode & 0o022


def test_two_builds_of_one_source_give_the_same_bytes(tmp_path, monkeypatch):
    # the compiler runs in its build folder with relative names: the library does not depend on the folder's
    # random name, so processes that build one library at once write the same bytes under its record
    libs = []
    for k in range(2):
        monkeypatch.setenv("MMG_CASADI_CACHE", str(tmp_path / f"c{k}"))
        f = _square("reproducible_square")
        compile_function(f)
        libs.append(library_path(f)[0].read_bytes())
    assert libs[0] == libs[1]
