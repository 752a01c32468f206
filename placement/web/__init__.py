"""The planning page: ``anchorplan serve`` (:mod:`placement.cli.serve`) serves a page that
shows the room, lets the user move anchors on their mounting surfaces and see the coverage
and the bound change, simulates the error at the receiver on demand, runs plans in the
background and exports what the command line exports.

:mod:`placement.web.scene` computes what the page shows (plain arrays and dicts, no web);
:mod:`placement.web.jobs` runs the long work (a plan in its own process, the field
simulation in a thread); :mod:`placement.web.app` is the ASGI application (FastAPI).
"""
