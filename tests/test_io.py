"""Generic file utilities: the temporary files and folders of killed writers are removed, live ones
kept; a complete folder takes an old one's place by renames."""

import os

from keyin.io import TEMPORARY_TAG, remove_stale_temporaries, replace_folder, temporary_path


def test_stale_temporaries_of_dead_writers_are_removed_live_ones_kept(tmp_path):
    dead = tmp_path / f".a.h5{TEMPORARY_TAG}99999999"  # no process has this id
    live = tmp_path / f".b.h5{TEMPORARY_TAG}{os.getpid()}"
    for path in (dead, live, tmp_path / "c.h5"):
        path.write_bytes(b"partial")
    assert remove_stale_temporaries(tmp_path) == [dead]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([live.name, "c.h5"])


def test_a_stale_temporary_folder_is_removed_a_live_one_kept(tmp_path):
    dead, live = tmp_path / f".d{TEMPORARY_TAG}99999999", tmp_path / f".l{TEMPORARY_TAG}{os.getpid()}"
    for folder in (dead, live):
        folder.mkdir()
        (folder / "shard.h5").write_bytes(b"partial")
    assert remove_stale_temporaries(tmp_path) == [dead]
    assert [p.name for p in tmp_path.iterdir()] == [live.name]


def test_a_complete_folder_replaces_the_old_one_by_renames(tmp_path):
    destination, new = tmp_path / "custom", temporary_path(tmp_path / "custom")
    for folder, content in ((destination, b"old"), (new, b"new")):
        folder.mkdir()
        (folder / "manifest.json").write_bytes(content)
    replace_folder(new, destination)
    assert (destination / "manifest.json").read_bytes() == b"new"
    assert [p.name for p in tmp_path.iterdir()] == ["custom"]
