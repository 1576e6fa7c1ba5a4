"""Python SDK for the MPM simulation service."""
