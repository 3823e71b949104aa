"""Many trials judged: the paper's protocol, how they run, the results files, and the statistics read from them."""
