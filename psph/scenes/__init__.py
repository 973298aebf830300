"""Built-in scenes (*.toml beside this file) and geometry builders."""
