"""Numbers the thesis reports, to print beside ours."""

# Table 4.5: metrics at the end of the 5000-iteration simulation
TABLE_4_5 = {
    "HSR": 0.82,
    "RSR": 0.90,
    "CDA": {"NAch": 1.73, "NSoc": 43.5, "NRes": 40.1, "NEng": 44.5, "all": 32.5},
    "CEDA": {"NAch": 1.73, "NSoc": 2.05, "NRes": 5.72, "NEng": 6.99, "all": 4.12},
}

# What Sections 4.2.3-4.2.5 and Chapter 5 say about Figs 4.3-4.5 (the figures themselves did
# not survive in the text we have, so these are the numbers and trends stated in the prose).
FIG_4_3_XI = [
    "RSR is greatly improved with xi larger than 0.5",
    "without the dominant motivation (xi = 0) the robot is insecure more than 60% of the time (RSR < 0.4)",
    "CDA and CEDA improve significantly for xi above 1",
    "a higher xi lowers HSR slightly",
]
FIG_4_4_PSEUDO = [
    "pseudo update raises HSR by about 10% (Chapter 5), most of all in the early stage",
    "without it NAch stays high for a few hundred iterations; with it early NAch is drastically lower",
    "RSR and CDA are roughly the same with or without; NEng shows no significant difference",
]
FIG_4_5_DOD = [
    "HSR rises with DoD; RSR falls almost linearly with DoD",
    "HSR is still about 0.6 at DoD = 0",
    "with DoD above 0.5 the robot is insecure more than half of the time (RSR < 0.5)",
    "a DoD around 0.2 balances HSR and RSR best",
]
THESIS_HSR_AT_DOD0 = 0.6
THESIS_PSEUDO_HSR_GAIN = 0.10
THESIS_RSR_AT_XI0_BELOW = 0.4
