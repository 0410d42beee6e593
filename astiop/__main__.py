from astiop.cli import app

app(prog_name="astiop")
