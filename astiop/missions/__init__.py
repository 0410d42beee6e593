"""Missions: several steps run one after the other through the gateway, each stored as it ends."""
