"""Facades: the same simulated device behind a modern fieldbus face, as mappings over the kind's
declared points (:mod:`devsim.core.points`) and, for drive profiles, its declared drive actions
(:class:`devsim.core.kit.DriveActions`), never code per kind.

* :mod:`devsim.facades.modbus_map` – the Modbus register map a kind's points give (pure);
* :mod:`devsim.facades.modbus_pdu` – the Modbus application layer: one table of function codes (pure);
* :mod:`devsim.facades.modbus_ident` – Read Device Identification's objects and responses (pure);
* :mod:`devsim.facades.modbus` – serving it (extra ``devsim-motion[modbus]``): Modbus TCP, and Modbus
  RTU on any devsim serial transport (a pty, raw TCP, RFC 2217);
* :mod:`devsim.facades.canopen_od` – the CANopen EDS of a kind (pure);
* :mod:`devsim.facades.cia402` – the CiA 402 state machine and profile modes (pure);
* :mod:`devsim.facades.canopen_node` – the device as canopen's local node (extra ``[can]``), reached
  from other processes through :mod:`devsim.transports.socketcand`;
* :mod:`devsim.facades.canopen_mapping` – the checks on a PDO mapping a master writes (CiA 301);
* :mod:`devsim.facades.mqtt_topics` – the devsim MQTT convention's topics and payloads (pure);
* :mod:`devsim.facades.mqtt_sparkplug` – Sparkplug B payloads through the Tahu binding (pure);
* :mod:`devsim.facades.mqtt` – publishing devices over MQTT (extra ``[mqtt]`` for the embedded
  amqtt broker and Sparkplug), and the embedded broker;
* :mod:`devsim.facades.mqtt_wire` – MQTT 5 and 3.1.1 packets (pure);
* :mod:`devsim.facades.mqtt_link` – devsim's own MQTT client connection over asyncio, one write per
  loop turn (the MQTT facade, the fleet's members and clients);
* :mod:`devsim.facades.mqtt_keepalive` – the links' pings, kept by a thread instead of a timer in the loop.
* :mod:`devsim.facades.opcua_space` – the OPC UA address space a kind's points give (pure);
* :mod:`devsim.facades.opcua` – a plant's devices on one asyncua OPC UA server (extra ``[opcua]``).
"""
