"""The README's examples run as written: its command sequence under "Using it", each line after
the ones above it in a fresh folder, and its Python example that builds a model in code. Run by
ctest with the other Python tests (LASH_BINARY and LASH_SOURCE_DIR set)."""
import os
import re
import subprocess

import lash

SOURCE = os.environ.get("LASH_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
LASH = os.environ.get("LASH_BINARY", os.path.join(SOURCE, "build", "lash"))


def readme() -> str:
    with open(os.path.join(SOURCE, "README.md"), encoding="utf-8") as f:
        return f.read()


def test_the_using_it_commands_run_in_order_in_a_fresh_folder(tmp_path):
    """Every command of the first block under "## Using it" exits 0, run in order in a folder
    holding only examples/ and build/lash, as a fresh clone after `make`."""
    section = readme().split("\n## Using it\n", 1)[1]
    block = re.match(r"\n*((?:    .*\n)+)", section).group(1)
    commands = [c.strip() for c in block.replace("\\\n", " ").splitlines()]
    assert len(commands) >= 5 and any("--from" in c for c in commands)
    (tmp_path / "build").mkdir()
    os.symlink(os.path.abspath(LASH), tmp_path / "build" / "lash")
    os.symlink(os.path.abspath(os.path.join(SOURCE, "examples")), tmp_path / "examples")
    for command in commands:
        run = subprocess.run(["bash", "-c", command], cwd=tmp_path, capture_output=True,
                             text=True, timeout=300)
        assert run.returncode == 0, f"{command}\n{run.stdout[-1000:]}\n{run.stderr[-2000:]}"


def test_the_python_example_builds_a_model_and_saves_it(tmp_path, monkeypatch):
    """The README's Python lines from `lash.Model.new` to the end of the block run as written and
    save a model file that `lash check` accepts and that runs."""
    block = readme().split("```python\n", 1)[1].split("```", 1)[0]
    code = block[block.index("m = lash.Model.new("):]
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "README.md", "exec"), {"lash": lash})
    saved = tmp_path / "my_mechanism.yaml"
    check = subprocess.run([LASH, "check", str(saved)], capture_output=True, text=True)
    assert check.returncode == 0, check.stderr
    result = lash.simulate(saved, t_end=0.01)
    assert result.ok and result.summary["clearance_joints"]["pin"]["impacts"] >= 0


def test_model_new_has_gravity_off_unless_given_as_a_model_file():
    """docs/model-format.md §2: gravity is off unless given; Model.new says the same."""
    assert "gravity" not in lash.Model.new("x").data
    assert lash.Model.new("x", gravity=[0, -9.81]).data["gravity"] == [0, -9.81]
