"""Pinocchio-native entry points: Python specifications of flexible links, models in memory."""
