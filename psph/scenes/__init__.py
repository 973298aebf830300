"""Built-in scenes: the *.toml files beside this file (data only; see psph.config.load)."""
