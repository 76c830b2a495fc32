"""``devsim monitor``: a terminal UI on a running plant (extra ``[monitor]``: textual).

:mod:`devsim.monitor.cli` is the command, :mod:`devsim.monitor.app` the textual app.
"""
