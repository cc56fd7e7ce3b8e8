"""The model behind a generated system, as the layers below the symbolic front end see it.

conmech.symbolic compiles a system from its Lagrangian or its equations and keeps the
compiled model (derivation, library, entry points) with the system it returns. The
integrators sometimes need to ask that model a question only it can answer (which kind of
system it is, for the Taylor method's refusal; which closed loop of a mechanism cannot
close at the initial positions, for the constrained solver's message; the Taylor
recurrences in SIMD lanes, for ensembles). They ask through
this interface, which the symbolic layer's :class:`conmech.symbolic.CompiledModel`
implements, so that no lower layer imports the optional sympy front end."""

__all__ = ["SystemModel", "model_of"]


class SystemModel:
    """What a generated system's model answers to the lower layers (the defaults: a model
    with nothing to say)."""

    #: "ode", "generalized" or "constrained" (None: not known)
    kind = None

    def closure_error(self, system, q0, t0=0.0):
        """None when the closed loops of `system` (made from this model) close at q0, or
        it has none; otherwise the ValueError naming the loop that does not close."""
        return None

    def taylor_batch_entries(self, lanes, order=None):
        """The entries of a batch library of this model's Taylor recurrences in `lanes`
        SIMD lanes (None: the machine's), written out for `order` when given, or None when
        the model has none (the ensembles' lane route asks)."""
        return None


def model_of(system):
    """The model behind a system made by conmech.symbolic: its :class:`CompiledModel`
    (derived expressions, source, library; a :class:`SystemModel`), also after
    ``with_params`` (the model is the first object such a system keeps). TypeError for any
    other system."""
    if isinstance(system, SystemModel):
        return system
    keep = getattr(system, "_keep", None)
    if isinstance(keep, tuple) and keep and isinstance(keep[0], SystemModel):
        return keep[0]
    raise TypeError("not a system made by conmech.symbolic")
