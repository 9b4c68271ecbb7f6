"""Readers check files while reading them: a file far over its size limit costs no more memory than the limit."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import pytest

from mmg_casadi.errors import InputError
from mmg_casadi.readers import MAX_BYTES, MAX_NESTING, csv_rows, load_json, load_toml, nesting_depth, read_text

MB = 1 << 20


def _peak_mb_of(code: str) -> tuple[float, str]:
    """Run ``code`` in a fresh interpreter; its peak RSS growth over the imports [MB] and its stderr."""
    script = textwrap.dedent("""
        import resource, sys
        import mmg_casadi.cli  # every reader imported: the baseline
        base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        from mmg_casadi.cli import main
        status = main(sys.argv[1:])
        print((resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - base) / 1024.0, status)
    """)
    out = subprocess.run([sys.executable, "-c", script, *code.split("\0")], capture_output=True, text=True,
                         timeout=300)
    growth, status = out.stdout.split()
    assert status == "2", out.stderr
    return float(growth), out.stderr


@pytest.mark.parametrize("kind", ["track", pytest.param("AIS", marks=pytest.mark.slow)])
def test_a_csv_far_over_its_limit_is_refused_while_read_with_bounded_memory(tmp_path, kind):
    # the issue: a 231 MB track CSV reached 4 GB and a 74 MB AIS CSV 1.7 GB before a limit refused them; read
    # as a stream they are refused at their byte limit (16 MB, 128 MB) with memory of a few MB
    limit = MAX_BYTES[kind]
    path = tmp_path / f"{kind}.csv"
    if kind == "track":
        rows = "".join(f"{k},{k * 0.5:.3f},1.0\n" for k in range(20_000))  # valid rows, the row limit aside
        head, body = "t,x,y\n", rows
        scenario = tmp_path / "s.toml"
        scenario.write_text('[settings]\nmethod = "none"\n[[ships]]\nname = "own"\nstart = [0.0, 0.0]\n'
                            'heading = 0.0\nspeed = 1.0\nwaypoints = [[50.0, 0.0]]\n[[ships]]\nname = "t"\n'
                            f'track = "{path.name}"\n')
        argv = ["simulate", str(scenario), "--out", str(tmp_path / "out")]
    else:
        body = "".join(f"{999000000 + k % 50},{k},{57.9 + 1e-6 * k:.6f},10.2\n" for k in range(100_000))
        head = "mmsi,time,lat,lon\n"
        argv = ["replay", str(path), "--own", "999000001", "--out", str(tmp_path / "o.toml")]
    with open(path, "w") as fh:  # a comment-free CSV over the limit: its rows repeated
        fh.write(head)
        while fh.tell() < limit + 4 * MB:
            fh.write(body)
    growth, err = _peak_mb_of("\0".join(argv))
    assert err.strip().splitlines()[-1].endswith(f"of at most {limit // MB} MB (MAX_BYTES), got '{path}: larger'") \
        or "rows" in err, err
    print(f"{kind}: {path.stat().st_size / MB:.0f} MB file, peak RSS growth {growth:.1f} MB")
    assert growth < 120, growth  # MB over the imports: the file's size is 20 MB (track) or 132 MB (AIS)
    assert not (tmp_path / "out").exists() and not (tmp_path / "o.toml").exists()


def test_text_readers_check_size_encoding_and_nesting(tmp_path):
    big = tmp_path / "big.toml"
    big.write_bytes(b"# " + b"x" * (MAX_BYTES["vessel"] + 10) + b"\n")
    with pytest.raises(InputError, match=r"a vessel file of at most 1 MB \(MAX_BYTES\)"):
        load_toml(big, "vessel")
    bom = tmp_path / "bom.json"
    bom.write_bytes(b"\xef\xbb\xbf" + json.dumps({"a": [1, 2]}).encode())
    assert load_json(bom, "GeoJSON") == {"a": [1, 2]}  # a byte-order mark is dropped
    bad = tmp_path / "bad.json"
    bad.write_bytes(b'{"a": "\xe9"}')
    with pytest.raises(InputError, match="expected a GeoJSON file in UTF-8, got 'byte 0xe9 at offset 7'"):
        load_json(bad, "GeoJSON")
    deep = tmp_path / "deep.json"
    deep.write_text("[" * (MAX_NESTING + 1) + "]" * (MAX_NESTING + 1))
    with pytest.raises(InputError, match="nested at most 32 levels deep"):
        load_json(deep, "GeoJSON")
    deep.write_text("[" * MAX_NESTING + "]" * MAX_NESTING)
    assert nesting_depth(load_json(deep, "GeoJSON")) == MAX_NESTING
    nan = tmp_path / "nan.json"
    nan.write_text('{"sog": NaN}')
    with pytest.raises(InputError, match="NaN is not a number JSON allows"):
        load_json(nan, "traffic situation")
    surrogate = tmp_path / "s.json"
    surrogate.write_text('{"name": "\\ud800"}')
    with pytest.raises(InputError, match="no unpaired surrogate"):
        load_json(surrogate, "traffic situation")
    with pytest.raises(InputError, match="an existing, readable scenario file"):
        read_text(tmp_path, "scenario")  # a directory


def test_csv_rows_stream_with_line_numbers_and_stop_at_the_row_limit(tmp_path):
    path = tmp_path / "r.csv"
    path.write_text("\ufeffa,b\n1,2\n3,4\n5,6\n", encoding="utf-8")
    assert [(n, r["a"]) for n, r in csv_rows(path, "track", max_rows=3)] == [(2, "1"), (3, "3"), (4, "5")]
    with pytest.raises(InputError, match="a track file of at most 2 rows"):
        list(csv_rows(path, "track", max_rows=2))
    path.write_bytes(b"a,b\n1,\xff\n")
    with pytest.raises(InputError, match="a track file in UTF-8"):
        list(csv_rows(path, "track", max_rows=10))
