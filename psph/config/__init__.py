"""The scene: its TOML schema, the rules between keys, materials, boundaries, and loading
(built-in scenes, files, `--set` overrides)."""
