"""Events for the drivers that stop at an event's first crossing and sample no state inside
a step (the closed-loop solve, constrained.solve): SciPy's event attributes checked once,
then what those drivers cannot do refused with their name."""
from .checks import event_settings

__all__ = ["first_crossing_events"]


def first_crossing_events(events, driver):
    """(function, terminal count (0 or 1), direction) per event for the driver named
    `driver`: ``resolution`` (sampling inside the steps) is solve_ivp's, and a terminal
    event stops at its first occurrence, so a count above 1 is refused."""
    settings = event_settings(events)
    for i, (_, count, _, res) in enumerate(settings):
        if res > 0:
            raise ValueError(f"events[{i}].resolution is not supported by {driver} (only by "
                             "conmech.solve_ivp)")
        if count > 1:
            raise ValueError(f"events[{i}].terminal: {driver} stops at the first occurrence "
                             "(terminal must be a boolean)")
    return [s[:3] for s in settings]
