"""Names read from user files stay inside their folder."""

import pytest

from keyin.errors import UnsafePathError
from keyin.paths import inside


def test_a_plain_name_resolves_inside(tmp_path):
    assert inside(tmp_path, "examples_brownian.png", "metrics.json") == (tmp_path / "examples_brownian.png").resolve()


@pytest.mark.parametrize("name", ["..", ".", "../x.png", "/tmp/x.png", "a/../../x.png"])
def test_names_that_leave_the_folder_are_refused(tmp_path, name):
    with pytest.raises(UnsafePathError, match="outside"):
        inside(tmp_path / "out", name, "metrics.json")


def test_a_symlink_out_of_the_folder_is_refused(tmp_path):
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "link").symlink_to(tmp_path)
    with pytest.raises(UnsafePathError):
        inside(tmp_path / "out", "link/x.png", "metrics.json")
