"""Facades: the same simulated device behind a modern fieldbus face, as mappings over the kind's
declared points (:mod:`devsim.core.points`), never code per kind.

* :mod:`devsim.facades.modbus_map` – the Modbus register map a kind's points give (pure);
* :mod:`devsim.facades.modbus` – serving that map with pymodbus (extra ``devsim-motion[modbus]``):
  Modbus TCP, and Modbus RTU on any devsim serial transport (a pty, raw TCP, RFC 2217).
"""
