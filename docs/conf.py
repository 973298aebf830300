"""Sphinx configuration of the psph documentation (`make docs`)."""

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))
sys.path.insert(0, str(DOCS.parent))

project = "psph"
author = "psph developers"
copyright = "2026, psph developers"

extensions = ["myst_parser", "scene_keys"]
source_suffix = {".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "data", "_ext", "**/.ipynb_checkpoints", "Thumbs.db",
                    ".DS_Store"]

# internal links must resolve: a MyST link to a missing page or anchor warns (and -W fails)
myst_all_links_external = False
myst_heading_anchors = 3
myst_enable_extensions = ["deflist"]
suppress_warnings = []
nitpicky = True

html_theme = "furo"
html_title = "psph"
html_static_path = []
