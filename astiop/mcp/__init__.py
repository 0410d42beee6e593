"""astiop as an MCP server: outside agents reach the robot through the one door, each actuation
approved by a person in an open console (or by the operator who started the server)."""
