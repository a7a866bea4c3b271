"""A small cty.dat and cty.csv, written here in AD1C's formats (longitudes WEST-positive), for
the parser's tests and the end-to-end test: never downloaded."""

from __future__ import annotations

CTY_DAT = """\
Japan:                    25:  45:  AS:   36.40:  -138.38:    -9.0:  JA:
    7J,7K,JA,JE,JR,
    =JA1XYZ/JD1<27.10/-142.20>;
Australia:                30:  59:  OC:  -23.70:  -132.33:   -10.0:  VK:
    AX,VK,=VK9XX(29)[54]<-10.50/-105.70>{AS};
United States:            05:  08:  NA:   37.53:    91.67:     5.0:  K:
    AA,K,N,W,=W1AW/KH6;
England:                  14:  27:  EU:   52.77:     1.47:     0.0:  G:
    2E,G,M;
France:                   14:  27:  EU:   46.00:    -2.00:    -1.0:  F:
    F,TM;
"""

CTY_CSV = """\
JA,Japan,339,AS,25,45,36.40,-138.38,-9.0,7J 7K JA JE JR =JA1XYZ/JD1<27.10/-142.20>;
VK,Australia,150,OC,30,59,-23.70,-132.33,-10.0,AX VK =VK9XX(29)[54]<-10.50/-105.70>{AS};
K,United States,291,NA,05,08,37.53,91.67,5.0,AA K N W =W1AW/KH6;
G,England,223,EU,14,27,52.77,1.47,0.0,2E G M;
F,France,227,EU,14,27,46.00,-2.00,-1.0,F TM;
"""
