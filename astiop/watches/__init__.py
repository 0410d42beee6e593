"""Watches and alerts, headless: a typed watch (model), read from plain language (words),
evaluated against the robot's sampled state with the built-in alerts (evaluator), and run on
its own (runner: `astiop watch run`)."""
