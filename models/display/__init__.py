"""Meshcat display of solutions: the live viewer (:mod:`.meshcat_display`, its server in
:mod:`.server`), what a solver's data says about contacts and frames (:mod:`.scene`), a camera and
floor that frame the whole motion (:mod:`.framing`) and the self-contained HTML animation
(:mod:`.html`), written as a compact page (:mod:`.page`, Collada packing in :mod:`.collada`).

Imported lazily by :mod:`crocopy.models` (meshcat is only needed to display).
"""

from .html import export_animation, export_html, export_html_from_solver, record_animation, static_html_commands
from .meshcat_display import MeshcatDisplay, start_meshcat_server, stop_meshcat_server
