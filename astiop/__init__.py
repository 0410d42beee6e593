"""astiop: the operator console for the LLM-controlled ASTIbot mobile robot."""

__version__ = "0.1.0"
