"""What the flight app's tests share."""


def console_text(cf):
    """The console lines the firmware printed so far (DEBUG_PRINT), text only."""
    return [text for _, _, text in cf.console.lines]
