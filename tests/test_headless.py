"""The core never imports textual: the CLI, tests and bench drive it without a terminal."""

import subprocess
import sys

CORE = [
    "astiop.config",
    "astiop.store",
    "astiop.sim",
    "astiop.sim.warehouse_map",
]


def test_core_does_not_import_textual():
    code = (
        "import importlib, sys\n"
        f"for m in {CORE!r}:\n"
        "    importlib.import_module(m)\n"
        "bad = sorted(m for m in sys.modules if m == 'textual' or m.startswith('textual.'))\n"
        "print(','.join(bad))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "", f"textual imported by the core: {out.stdout}"
