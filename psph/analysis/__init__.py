"""Post-processing of run directories: pictures (`psph plot`) and the reports of
`python -m psph.analysis.pressure | particle | porosity`."""
