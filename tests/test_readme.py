"""The README's Python example runs as written."""

import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def readme_example():
    """The README's ```python block whose first line is ``# README example``."""
    blocks = re.findall(r"^```python\n(.*?)^```", README.read_text(), re.S | re.M)
    found = [block for block in blocks if block.startswith("# README example\n")]
    assert len(found) == 1, "README.md needs one ```python block starting '# README example'"
    return found[0]


def test_readme_example_runs(capsys):
    exec(compile(readme_example(), str(README), "exec"), {"__name__": "readme"})
    out = capsys.readouterr().out
    assert "settlement" in out
    assert "Newton iterations" in out
