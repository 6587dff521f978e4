"""Numbers the thesis reports, to print beside ours."""

# Table 4.5: metrics at the end of the 5000-iteration simulation
TABLE_4_5 = {
    "HSR": 0.82,
    "RSR": 0.90,
    "CDA": {"NAch": 1.73, "NSoc": 43.5, "NRes": 40.1, "NEng": 44.5, "all": 32.5},
    "CEDA": {"NAch": 1.73, "NSoc": 2.05, "NRes": 5.72, "NEng": 6.99, "all": 4.12},
}
