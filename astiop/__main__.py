from astiop.cli import run

run()
