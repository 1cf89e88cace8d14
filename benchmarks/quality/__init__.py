"""Quality: the controllers and agents against the paper's claims and the optimum."""
