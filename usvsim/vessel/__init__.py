"""The vessel block: parameter registry, the pure CasADi model, the autopilot, the batched plant
and its generated C.
"""
