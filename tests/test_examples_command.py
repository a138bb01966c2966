"""``hydroarm examples [--copy DIR]`` (issue 33): every example listed with one line; copied
into a folder without overwriting anything (the one-line error contract)."""

from pathlib import Path

from hydroarm.cli import main
from hydroarm.io.examples import DESCRIPTION_CHARS, examples_folder, list_examples

ROOT = Path(__file__).resolve().parents[1]


def test_examples_folder_is_the_repositorys_in_a_checkout():
    assert examples_folder() == ROOT / "examples"


def test_every_example_is_listed_with_one_line(capsys):
    assert main(["examples"]) == 0
    out = capsys.readouterr().out.splitlines()
    names = sorted(p.name for p in (ROOT / "examples").iterdir() if p.is_file())
    listed = [ln.split()[0] for ln in out[1:]]
    assert listed == names
    for e in list_examples():
        assert e.description, e.name
        assert "\n" not in e.description and len(e.description) <= DESCRIPTION_CHARS, e.name
    by_name = {e.name: e.description for e in list_examples()}
    assert by_name["position_servo.toml"] == (
        "An industrial electro-hydraulic position servo built from components"
    )
    assert by_name["excavator_cycle.csv"].startswith("data: columns t_s, boom_deg")


def test_copy_copies_every_file_byte_for_byte(tmp_path, capsys):
    dest = tmp_path / "ex"
    assert main(["examples", "--copy", str(dest)]) == 0
    names = sorted(p.name for p in (ROOT / "examples").iterdir() if p.is_file())
    assert sorted(p.name for p in dest.iterdir()) == names
    for n in names:
        assert (dest / n).read_bytes() == (ROOT / "examples" / n).read_bytes()
    assert f"{len(names)} example files copied" in capsys.readouterr().out


def test_copy_refuses_to_overwrite_and_copies_nothing(tmp_path, capsys):
    dest = tmp_path / "ex"
    dest.mkdir()
    (dest / "position_servo.toml").write_text("mine")
    assert main(["examples", "--copy", str(dest)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("hydroarm: error: --copy: ")
    assert "position_servo.toml already exist" in err[0]
    assert [p.name for p in dest.iterdir()] == ["position_servo.toml"]
    assert (dest / "position_servo.toml").read_text() == "mine"


def test_copy_refuses_a_file_or_a_missing_parent(tmp_path, capsys):
    f = tmp_path / "f"
    f.write_text("x")
    assert main(["examples", "--copy", str(f)]) == 2
    assert (
        capsys.readouterr().err.strip() == f"hydroarm: error: --copy: {f} is a file, not a folder"
    )
    missing = tmp_path / "no" / "ex"
    assert main(["examples", "--copy", str(missing)]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"hydroarm: error: --copy: {missing}: folder {missing.parent} does not exist"
    assert not missing.parent.exists()
