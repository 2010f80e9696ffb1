"""ROS's own formats: ROS 1 bags and rosbag2 folders (read with rosbags), and ROS messages
(CDR, ROS 1 serialization) decoded field by field or in columns, with the definitions a log
lacks.

Modules: :mod:`.bags` :class:`~fretc.logs.ros.bags.BagSource`, :mod:`.ros1_linear` a ROS 1
bag without its index, :mod:`.rosbag2_storage` rosbag2's sqlite3 storage as rosbag2 reads
it; :mod:`.selective` decoding only the bound fields, message by message (the reference),
:mod:`.columnar` the bound fields of many CDR messages at once (numpy); :mod:`.known_types`
schemas that lie about a standard type, :mod:`.msg_path` a team's own ``.msg``/``.idl`` files
(``--msg-path``), :mod:`.standard_services` the standard services' event types.

May import: ``fretc.common``, :mod:`fretc.logs.base` and the log layer's shared modules
(:mod:`fretc.logs.decoding`, :mod:`fretc.logs.reorder`); not the other formats'
subpackages.
"""
