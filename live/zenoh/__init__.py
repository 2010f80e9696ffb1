"""The Zenoh transport (``fretc watch zenoh://HOST:PORT``, ``fretc replay --serve
zenoh://``): a Zenoh session that reads (or publishes) a ROS 2 graph's topics as rmw_zenoh
(or zenoh-bridge-ros2dds) puts them.

Modules: :mod:`.client` the watch's session (liveliness tokens, attachments); :mod:`.serve` a
recorded log published as a ROS 2 node on rmw_zenoh would.

May import: the layers before ``fretc.live`` and the live layer's shared modules
(:mod:`fretc.live.protocol`, :mod:`fretc.live.events`, :mod:`fretc.live.merge`,
:mod:`fretc.live.ros2_names`); not the other transports' subpackages.
"""
