"""The editor's type and unit of window and service bindings (hover, completion): a window
keeps the unit of what it aggregates (a mean of m/s is m/s), a count is a count, ``rate`` is
in Hz and ``waiting`` in seconds."""

from fretc.editor.bindings_info import read_bindings

TEXT = '''[tick]
period = "100 ms"
[types]
"/odom" = "nav_msgs/msg/Odometry"
[variables]
m = "mean(/odom.twist.twist.linear.x, 2s)"
p = "percentile(/odom.twist.twist.linear.x, 95, 10s)"
lo = "min(/odom.twist.twist.linear.x, 50 messages)"
r = "rate(/odom, 1s)"
w = "waiting(/arm)"
n = "count(/odom.twist.twist.linear.x > 0, 1min)"
'''


def test_window_bindings_have_the_type_and_unit_of_their_values():
    got = {k: (v.type, v.unit) for k, v in read_bindings(TEXT, "x").variables.items()}
    assert got == {"m": ("number", "m/s"), "p": ("number", "m/s"), "lo": ("number", "m/s"),
                   "r": ("number", "Hz"), "w": ("number", "s"), "n": ("number", "count")}
