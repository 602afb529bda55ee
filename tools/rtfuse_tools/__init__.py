"""Python helpers shared by the rtfuse tools (log I/O, generated LCM types)."""
