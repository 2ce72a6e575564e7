"""The task block: scenario, observations, radar image, reward, the batch simulator and the
Gymnasium environments.
"""
