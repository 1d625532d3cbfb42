"""Follower types as plug-ins: one folder per type, one contract they all fill in.
"""
