"""The agent: LLM clients, the embedded model, the rules baseline, and the turn."""
