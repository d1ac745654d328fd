"""Exports of a fitted motion, one module per file format."""
