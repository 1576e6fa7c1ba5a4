"""Explicit material point method solver: scene in, HDF5 result out."""
