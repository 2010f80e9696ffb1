"""What the live tests read in an unknown verdict's reason."""


def left_for_good(reason: str | None, topic: str) -> bool:
    """Whether ``reason`` says ``topic``'s publisher left the run for good: the cut where it
    left, past the clock's last tick ("the publisher of ... left"), or the unknown ticks of
    its gap (``publisher_left_for_good``); which one depends on whether a tick of the clock
    came after the last message used before it left, as the transport delivered them."""
    return reason is not None and (f"publisher of {topic} left" in reason
                                   or "publisher_left_for_good" in reason)
