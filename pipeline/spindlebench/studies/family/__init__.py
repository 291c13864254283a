"""What every study type shares: the study family file (experiment axes), the experiments it
expands to, climates, seeds and the method specs scored in every study."""
