"""The field cache survives misuse: a checksum detects a corrupt entry,
which is recomputed and overwritten; an unwritable or vanished cache warns and keeps the
field in memory; temporary names are unique (threads of one process share an entry); a
size cap evicts the least recently used entries. And the field resolution is a keyword of
the sampling models."""

from __future__ import annotations

import os
import shutil
import threading
from pathlib import Path

import numpy as np
import pytest

import rhoprop as rp
from rhoprop import cache
from rhoprop.density import FieldResolution, FromFunction
from rhoprop.density.field import FIELD_FORMAT
from rhoprop.errors import CacheWarning

RES = FieldResolution(time=3 * 3600.0, altitude=50e3, latitude=30.0, longitude=60.0)
WINDOW = ("2002-09-07T00:00", "2002-09-07T12:00")
BAND = (350e3, 450e3)


class Counting:
    """A smooth density function that counts its calls (one per sampled field)."""

    def __init__(self, scale: float = 1.0, hook=None) -> None:
        self.calls = 0
        self.scale = scale
        self.hook = hook

    def __call__(self, t, lat, lon, alt):
        self.calls += 1
        if self.hook is not None:
            self.hook()
        hours = (t - np.datetime64("2002-09-07", "ns")) / np.timedelta64(1, "h")
        mean = self.scale * 1e-12 * np.exp(-(alt - 4e5) / 6e4) * (1 + 0.01 * hours)
        return mean * (1 + 0.1 * np.cos(np.radians(lat))), 0.1 * mean


def model(key: str = "counting v1", **kwargs) -> tuple[FromFunction, Counting]:
    fn = Counting(**kwargs)
    return FromFunction(fn, cache_key=key), fn


def field(m: FromFunction, **kwargs):
    return m.field(*WINDOW, altitude_range=BAND, resolution=RES, **kwargs)


def entries(root: Path) -> list[Path]:
    return sorted((root / "fields").glob("*.npz"))


@pytest.fixture
def root(tmp_path, monkeypatch):
    monkeypatch.setenv("RHOPROP_CACHE", str(tmp_path / "cache"))
    monkeypatch.delenv(cache.MAX_BYTES_ENV, raising=False)
    return tmp_path / "cache"


def test_hit_reads_the_entry_with_its_checksum(root):
    m, fn = model()
    first = field(m)
    (path,) = entries(root)
    with np.load(path) as saved:
        assert set(saved.files) == {"ln_mean", "rel_sigma", "key", "checksum"}
        assert str(saved["checksum"]) == cache.checksum(
            {k: saved[k] for k in ("ln_mean", "rel_sigma", "key")}
        )
        assert f'"format": {FIELD_FORMAT}' in str(saved["key"])
    second = field(m)
    assert fn.calls == 1
    np.testing.assert_array_equal(first.ln_mean, second.ln_mean)
    np.testing.assert_array_equal(first.rel_sigma, second.rel_sigma)


@pytest.mark.parametrize("damage", ["garbage", "truncated", "empty", "npy", "checksum", "nan"])
def test_corrupt_entry_is_recomputed_and_overwritten(root, damage):
    m, fn = model()
    good = field(m)
    (path,) = entries(root)
    data = path.read_bytes()
    if damage == "garbage":
        path.write_bytes(b"not an npz at all")
    elif damage == "truncated":
        path.write_bytes(data[: len(data) // 2])
    elif damage == "empty":
        path.write_bytes(b"")
    elif damage == "npy":
        with open(path, "wb") as out:
            np.save(out, np.zeros(3))
    elif damage == "nan":
        # NaN written with a checksum that matches (it gave "ln_mean[0] must be finite"
        # from the core, naming no file): recomputed like any corrupt entry.
        with np.load(path) as saved:
            arrays = {k: saved[k] for k in saved.files if k != "checksum"}
        arrays["ln_mean"] = np.full_like(arrays["ln_mean"], np.nan)
        cache.store_entry(path, arrays)
    else:
        # A valid npz whose values changed after the checksum was taken (e.g. bit rot
        # behind a good zip CRC, or an edit by hand).
        with np.load(path) as saved:
            arrays = {k: saved[k] for k in saved.files}
        arrays["ln_mean"] = arrays["ln_mean"] + 1.0
        with open(path, "wb") as out:
            np.savez(out, **arrays)
    with pytest.warns(CacheWarning, match="recomputing"):
        again = field(m)
    assert fn.calls == 2
    np.testing.assert_array_equal(again.ln_mean, good.ln_mean)
    # Overwritten: the next run reads it without a warning (warnings are errors here).
    field(m)
    assert fn.calls == 2 and entries(root) == [path]


def test_unwritable_cache_keeps_the_field_in_memory(tmp_path, monkeypatch):
    # The cache "directory" is a file: nothing can be created under it (works as root too).
    blocker = tmp_path / "not-a-directory"
    blocker.write_text("")
    monkeypatch.setenv("RHOPROP_CACHE", str(blocker))
    m, fn = model()
    reference = field(m, cache=False)
    with pytest.warns(CacheWarning, match="could not write cache entry .* kept in memory"):
        f = field(m)
    np.testing.assert_array_equal(f.ln_mean, reference.ln_mean)
    assert fn.calls == 2
    # The field works for propagation as well.
    state = rp.scenarios.paper_state("2002-09-07T00:00")
    with pytest.warns(CacheWarning):
        tr = rp.propagate(state, rp.scenarios.paper_spacecraft(), m, 3600.0)
    assert np.isfinite(tr.positions).all()


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only directories")
def test_read_only_cache_directory(root):
    (root / "fields").mkdir(parents=True)
    os.chmod(root / "fields", 0o500)
    try:
        m, _ = model()
        with pytest.warns(CacheWarning, match="could not write"):
            f = field(m)
        assert np.isfinite(f.ln_mean).all()
    finally:
        os.chmod(root / "fields", 0o700)


def test_cache_vanishing_during_sampling(root):
    # Deleted while the field is computed: the directory is made again and the entry
    # written; replaced by a file: a warning, and the field from memory.
    m, _ = model(hook=lambda: shutil.rmtree(root, ignore_errors=True))
    root.mkdir(parents=True)
    f = field(m)
    assert len(entries(root)) == 1 and np.isfinite(f.ln_mean).all()

    def replace_by_file() -> None:
        shutil.rmtree(root, ignore_errors=True)
        root.write_text("")

    m2, _ = model("other", hook=replace_by_file)
    with pytest.warns(CacheWarning, match="could not write"):
        f2 = field(m2)
    np.testing.assert_array_equal(f2.ln_mean, f.ln_mean)


def test_threads_sampling_the_same_key(root):
    m, fn = model()
    barrier = threading.Barrier(4)
    results, failures = [], []

    def work() -> None:
        try:
            barrier.wait()
            results.append(field(m))
        except Exception as err:  # pragma: no cover - reported below
            failures.append(err)

    threads = [threading.Thread(target=work) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not failures
    assert fn.calls == 1  # one computes, the others read its entry
    for r in results[1:]:
        np.testing.assert_array_equal(r.ln_mean, results[0].ln_mean)
    assert len(entries(root)) == 1
    assert not [p for p in (root / "fields").iterdir() if p.suffix == ".tmp"]


def test_concurrent_writers_never_collide(tmp_path):
    # Many writers of one entry (threads here; processes alike: the temporary name holds
    # pid, thread id and random bytes), each renaming a complete file into place.
    path = tmp_path / "fields" / "entry.npz"
    failures = []

    def write(k: int) -> None:
        try:
            for i in range(10):
                assert cache.store_entry(path, {"x": np.full(1000, float(k * 100 + i))})
        except Exception as err:  # pragma: no cover - reported below
            failures.append(err)

    threads = [threading.Thread(target=write, args=(k,)) for k in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not failures
    loaded = cache.load_entry(path)
    assert loaded is not None and np.ptp(loaded["x"]) == 0
    assert [p.name for p in path.parent.iterdir()] == ["entry.npz"]


def test_size_cap_evicts_the_least_recently_used(root, monkeypatch):
    m1, f1 = model("a")
    field(m1)
    (size,) = {p.stat().st_size for p in entries(root)}
    monkeypatch.setenv(cache.MAX_BYTES_ENV, str(int(2.5 * size)))
    m2, f2 = model("b", scale=2.0)
    field(m2)
    a, b = (p for p in entries(root))
    by_key = {m: p for p in (a, b) for m in ("a", "b") if f'"{m}"' in str(np.load(p)["key"])}
    # Make "a" old and "b" older, then use "a": "b" is now the least recently used.
    os.utime(by_key["a"], (1000, 1000))
    os.utime(by_key["b"], (500, 500))
    field(m1)
    assert f1.calls == 1
    m3, _ = model("c", scale=3.0)
    field(m3)
    left = entries(root)
    assert len(left) == 2 and by_key["b"] not in left and by_key["a"] in left
    assert sum(p.stat().st_size for p in left) <= 2.5 * size
    # "b" is recomputed when needed again.
    field(m2)
    assert f2.calls == 2


def test_size_cap_setting(root, monkeypatch):
    assert cache.max_bytes() == cache.DEFAULT_MAX_BYTES == 2_000_000_000
    monkeypatch.setenv(cache.MAX_BYTES_ENV, "5e8")
    assert cache.max_bytes() == 500_000_000
    monkeypatch.setenv(cache.MAX_BYTES_ENV, "0")  # 0 disables writing, silently
    m, fn = model()
    field(m)
    field(m)
    assert fn.calls == 2 and entries(root) == []
    for bad in ("-1", "lots", "inf", "nan"):
        monkeypatch.setenv(cache.MAX_BYTES_ENV, bad)
        with pytest.raises(ValueError, match="RHOPROP_CACHE_MAX_BYTES must be a number"):
            cache.max_bytes()


def test_resolution_keyword_of_the_sampling_models(root):
    res = FieldResolution(time=2 * 3600.0, altitude=20e3, latitude=10.0, longitude=20.0)
    fn = Counting()
    m = FromFunction(fn, resolution=res)
    assert m.resolution is res
    f = m.field(*WINDOW, altitude_range=BAND)
    assert np.diff(f.latitudes)[0] == 10.0 and np.diff(f.longitudes)[0] == 20.0
    assert np.diff(f.altitudes)[0] == 20e3 and np.diff(f.times).max() <= 7200.0
    # propagation samples at the model's resolution too
    state = rp.scenarios.paper_state("2002-09-07T00:00")
    core = m.atmosphere(state, 3600.0)
    assert core is not None
    # an explicit resolution still wins
    g = m.field(*WINDOW, altitude_range=BAND, resolution=RES)
    assert np.diff(g.longitudes)[0] == 60.0
    # default: FieldResolution()'s spacing
    d = FromFunction(fn).field(*WINDOW, altitude_range=BAND)
    assert np.diff(d.longitudes)[0] == FieldResolution().longitude
    from test_pcarom import synthetic

    assert synthetic(resolution=res).resolution is res
    sw = rp.SpaceWeather()
    assert rp.density.Msis("2.1", sw, resolution=res).resolution is res
    assert rp.density.Msis("2.1", sw).resolution is None
    for make in (
        lambda: FromFunction(fn, resolution=(1, 2, 3, 4)),
        lambda: synthetic(resolution="fine"),
        lambda: rp.density.Msis("2.1", sw, resolution=3600.0),
    ):
        with pytest.raises(TypeError, match=r"resolution must be a rhoprop\.density\.Field"):
            make()
