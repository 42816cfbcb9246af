"""Files are written atomically (``activevision.io``): whole or not at all, and a write that
cannot happen names the file asked for, not the temporary one beside it."""

import os

import pytest

from activevision.io import file_sha256, write_csv, write_text


def test_a_write_replaces_the_file_whole_and_leaves_no_temporary(tmp_path):
    target = tmp_path / "a" / "b.txt"
    write_text(target, "one")
    write_text(target, "two")
    assert target.read_text() == "two"
    assert os.listdir(target.parent) == ["b.txt"]


def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path, monkeypatch):
    target = tmp_path / "b.txt"
    write_text(target, "old")

    def fail(path):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("activevision.io.fsync_path", fail)
    with pytest.raises(OSError, match="No space"):
        write_text(target, "new")
    assert target.read_text() == "old"
    assert os.listdir(tmp_path) == ["b.txt"]


def test_a_write_that_fails_on_a_full_disk_names_the_file_asked_for(tmp_path):
    # a full disk failed plot, report, export with "[Errno 28] No space left on device" alone
    from activevision.io import atomic_path

    target = tmp_path / "plots" / "reward.png"
    with pytest.raises(OSError) as caught, atomic_path(target):
        raise OSError(28, "No space left on device")  # what a file's write() raises
    assert caught.value.errno == 28
    assert str(caught.value) == f"[Errno 28] cannot write {target}: No space left on device"
    assert os.listdir(target.parent) == []
    other = tmp_path / "input.csv"  # an error that names its own file is left as it was
    with pytest.raises(FileNotFoundError) as caught, atomic_path(target):
        other.read_text()
    assert caught.value.filename == str(other)


def test_a_write_that_cannot_start_names_the_file_asked_for(tmp_path):
    (tmp_path / "plain").write_text("a file, not a folder")
    target = tmp_path / "plain" / "x.png"
    with pytest.raises(OSError) as caught:
        write_text(target, "x")
    assert f"cannot write {target}" in str(caught.value)
    assert ".tmp" not in str(caught.value)


def test_a_write_over_a_folder_names_it_before_the_work_and_leaves_no_temporary(tmp_path):
    # it was refused by the rename at the end: "Is a directory: '.out.x1y2.tmp' -> 'out'"
    from activevision.io import atomic_path

    (tmp_path / "out").mkdir()
    entered = []
    with pytest.raises(IsADirectoryError) as caught, atomic_path(tmp_path / "out"):
        entered.append(True)
    assert str(caught.value).endswith(f"cannot write {tmp_path / 'out'}: it is a directory")
    assert not entered and os.listdir(tmp_path) == ["out"]
    with pytest.raises(IsADirectoryError, match="it is a directory"):
        write_text(tmp_path / "out", "x")


def test_read_csv_names_the_line_of_a_row_cut_short_or_run_on_and_a_file_not_text(tmp_path):
    from activevision.io import read_csv

    path = tmp_path / "a.csv"
    path.write_text("x,y\n1,2\n3\n")
    with pytest.raises(ValueError, match=r"a\.csv line 3 has fewer cells than its header"):
        read_csv(path)
    path.write_text("x,y\n1,2,3\n")
    with pytest.raises(ValueError, match=r"a\.csv line 2 has more cells than its header"):
        read_csv(path)
    # the line in the file, past blank lines and a cell of two lines (a count of rows: 3)
    path.write_text('x,y\n1,"a\nb"\n\n\n3\n')
    with pytest.raises(ValueError, match=r"a\.csv line 6 has fewer cells than its header"):
        read_csv(path)
    path.write_bytes(b"\xff\xfex,y\n")
    with pytest.raises(ValueError, match=r"a\.csv is damaged .*UnicodeDecodeError"):
        read_csv(path)
    path.write_text("x,y\n1,2\n")
    assert read_csv(path) == [{"x": "1", "y": "2"}]
    write_csv(path, [{"x": "Müller", "y": "—"}])  # UTF-8 both ways, whatever the locale
    assert path.read_bytes() == "x,y\r\nMüller,—\r\n".encode()
    assert read_csv(path) == [{"x": "Müller", "y": "—"}]


def test_read_csv_names_a_file_without_its_header_or_a_column_asked_for(tmp_path):
    """Every CSV this package writes starts with its header: an empty file was read as a
    table of no rows (compare resumed it as no levels played, replacing it)."""
    from activevision.io import read_csv

    path = tmp_path / "a.csv"
    for text in ("", "\n\n"):
        path.write_text(text)
        with pytest.raises(ValueError, match=r"a\.csv is empty \(no header row\)"):
            read_csv(path)
    path.write_text("x,y\n")
    assert read_csv(path) == [] and read_csv(path, ("y", "x")) == []
    with pytest.raises(ValueError, match=r"a\.csv has no 'z' column"):
        read_csv(path, ("x", "z"))  # with no rows too
    path.write_text("x,y\n1,2\n")
    with pytest.raises(ValueError, match=r"a\.csv has no 'z' column"):
        read_csv(path, ("z",))


def test_read_json_refuses_a_key_named_twice_naming_it_and_the_file(tmp_path):
    """json.loads keeps the last of two values of one key without a word: a config's
    ``"seed": 1`` was silently replaced by a forgotten ``"seed": 2`` further down."""
    from activevision.io import loads_json, read_json

    path = tmp_path / "c.json"
    path.write_text('{"run": {"seed": 1, "lr": 2, "seed": 2}}')
    with pytest.raises(ValueError, match=r"c\.json: duplicate key 'seed'"):
        read_json(path)
    with pytest.raises(ValueError, match="duplicate key 'a'"):
        loads_json('[{"b": 1}, {"a": 1, "a": 1}]')  # in any object, even with equal values
    # the same key in two objects, and keys that differ only in case, are not duplicates
    assert loads_json('[{"a": 1}, {"a": 2, "A": 3}]') == [{"a": 1}, {"a": 2, "A": 3}]


def test_read_csv_refuses_a_last_line_without_its_end_of_line(tmp_path):
    """Every CSV activevision writes ends each row with an end of line: a file cut inside
    its last cell (``0.12`` of ``0.1234``) has all its cells and was read as whole. A log
    still being written (``live``) is read without that line."""
    from activevision.io import read_csv

    path = tmp_path / "a.csv"
    path.write_bytes(b"x,y\r\n1,2\r\n3,0.12")
    with pytest.raises(ValueError, match=r"a\.csv line 3 has no end of line"):
        read_csv(path)
    assert read_csv(path, live=True) == [{"x": "1", "y": "2"}]
    path.write_bytes(b"x,y")  # the header itself cut: no table at all
    with pytest.raises(ValueError, match=r"a\.csv line 1 has no end of line"):
        read_csv(path)
    with pytest.raises(ValueError, match=r"a\.csv is empty"):
        read_csv(path, live=True)
    path.write_bytes(b'x,y\r\n1,"two\nlines"\n')  # a quoted end of line inside a cell
    assert read_csv(path) == [{"x": "1", "y": "two\nlines"}]


def test_file_sha256_is_the_standard_digest_of_the_file_bytes(tmp_path):
    # FIPS 180-2's example: SHA-256("abc")
    path = tmp_path / "abc.txt"
    path.write_bytes(b"abc")
    assert file_sha256(path) == ("ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad")
