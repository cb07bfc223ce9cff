"""pytest plugin registered by rockbench (entry point ``pytest11``)."""
