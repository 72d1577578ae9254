"""gliderplan.planner"""
