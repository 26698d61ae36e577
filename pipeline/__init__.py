"""roughcontact engine: scenes, stage graph, result store and command line.

The engine knows no physics. Physical stages live in the :mod:`stages` package and
declare what they read and write through :class:`pipeline.stage.Stage`.
"""

__version__ = "0.1.0"
