"""gliderplan.reports: what the tradeoffs look like to a reader. The board comparison
(`gliderplan compare-sbc`: table, JSON, CSV, plot) and the offline HTML report
(`gliderplan report`): one self-contained page and the CSV behind each of its figures."""
