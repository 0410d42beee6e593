"""Hosting the model: the LLM clients (llm), model specs (specs), the embedded llama.cpp server
in its own process (embedded, model_process, model_spawn, prompt_cache), the reply stream and
the endpoint probe. The turn's logic (intent, planner, gate, grounding, turn) is beside this
package, in astiop.agent."""
