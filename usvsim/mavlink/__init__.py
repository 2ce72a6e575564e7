"""The MAVLink block: the typed messages, the pymavlink adapter, missions, the bridge, and the
plant as a MAVLink vehicle or physics backend.
"""
