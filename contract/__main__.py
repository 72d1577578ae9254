"""`python -m gliderplan.contract`: print runtime/include/gp_contract.h."""

from gliderplan.contract.c_header import c_header

print(c_header(), end="")
