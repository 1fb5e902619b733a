"""Result tables, ParaView files, figures and the assembly stress report."""
