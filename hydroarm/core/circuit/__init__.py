"""Circuits of any shape on one system kernel (issue 28; docs/components.md "Circuits")."""
