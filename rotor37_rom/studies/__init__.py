"""Studies built on the models and the integrator: interaction maps, NFRC and continuation, model choice."""
