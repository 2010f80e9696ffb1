"""The DDS transport (``fretc watch dds://DOMAIN``, ``fretc replay --serve dds://``): a Cyclone
DDS participant that reads (or publishes) a ROS 2 graph's topics as ROS 2 names them on DDS.

Modules: :mod:`.client` the watch's reader (publishers' liveliness, the release watermark);
:mod:`.idl_types` Cyclone DDS types built from message definitions and raw CDR samples;
:mod:`.serve` a recorded log published as a ROS 2 node would.

May import: the layers before ``fretc.live`` and the live layer's shared modules
(:mod:`fretc.live.protocol`, :mod:`fretc.live.events`, :mod:`fretc.live.merge`,
:mod:`fretc.live.ros2_names`); not the other transports' subpackages.
"""
