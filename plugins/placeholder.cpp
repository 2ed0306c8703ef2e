// placeholder until the first plugin lands
