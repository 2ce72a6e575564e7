"""The helmsman block: the Helmsman protocol and the one registry of helmsmen by name."""
