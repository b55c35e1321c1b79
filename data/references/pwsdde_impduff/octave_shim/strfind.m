function r = strfind(varargin)
% MATLAB's strfind([], pattern) is []; Octave 7's is an error.
if isempty(varargin{1}) && ~ischar(varargin{1}) && ~iscell(varargin{1})
  r = [];
else
  r = builtin('strfind', varargin{:});
end
end
