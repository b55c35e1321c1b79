"""The paper's figure protocols, as the book's chapters run them (the library's
``endstop::paper``): ``endstop.paper.fig13.run()``."""

from . import fig13

__all__ = ["fig13"]
