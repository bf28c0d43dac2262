"""docs/python.md against the module: every public name documented, the first program runs."""
import pathlib
import re

import ceode

DOC = pathlib.Path(__file__).resolve().parents[2] / "docs" / "python.md"


def test_every_public_name_and_method_is_in_the_python_guide():
    text = DOC.read_text()
    for name in ceode.__all__:
        assert name in text, name
    for cls in (ceode.Integrator, ceode.LinearStructure):
        for name in dir(cls):
            if not name.startswith("_"):
                assert re.search(r"`%s[`(]" % name, text), "%s.%s" % (cls.__name__, name)


def test_the_first_program_of_the_python_guide_runs():
    text = DOC.read_text()
    block = text.split("## A first program", 1)[1].split("```python\n", 1)[1].split("```", 1)[0]
    exec(compile(block, str(DOC), "exec"), {})
