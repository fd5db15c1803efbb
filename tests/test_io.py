"""Generic file utilities: the temporary files of killed writers are removed, live ones kept."""

import os

from keyin.io import TEMPORARY_TAG, remove_stale_temporaries


def test_stale_temporaries_of_dead_writers_are_removed_live_ones_kept(tmp_path):
    dead = tmp_path / f".a.h5{TEMPORARY_TAG}99999999"  # no process has this id
    live = tmp_path / f".b.h5{TEMPORARY_TAG}{os.getpid()}"
    for path in (dead, live, tmp_path / "c.h5"):
        path.write_bytes(b"partial")
    assert remove_stale_temporaries(tmp_path) == [dead]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([live.name, "c.h5"])
